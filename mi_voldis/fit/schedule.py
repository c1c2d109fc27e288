"""The coarse-to-fine schedule of a fit, as data: which resolution from which step, and how many steps.

Given explicitly (``resolution_schedule`` and ``steps_full``), it is used as it is. Otherwise it is
derived from the capture and the time budget once the first, coarse stage has run
``calibration_steps`` steps (and is then frozen in the fit's checkpoint, so a resumed fit follows it):

* the final resolution (``resolution`` 'auto') makes a voxel about ``pixels_per_voxel`` pixels of the
  training views wide where their rays end (:func:`capture_survey`), at most ``max_resolution``,
  and no finer than lets the last stage end ``min_observations`` training rays in every surface cell
  in its share of the budget (:func:`affordable_resolution`): a sharp grid seen too few times is worse
  than a coarser one seen often. Observations, not passes over the pixels, are the currency: a capture
  with more views never gets a coarser grid than the same scene with fewer;
* ``stages`` resolutions double up to it, each starting at its ``stage_starts`` fraction of the steps;
* the stages after the coarse one sample every whole voxel where, so costed, the final grid is still
  bound by the memory or the pixels rather than by the observations the budget buys (``step_voxels``
  'auto', :func:`choose_step`): the cheaper step then buys more steps on that grid and halves the
  samples a fitted ray evaluates; elsewhere every half voxel;
* the number of steps (``steps_full``, or from ``minutes``) fills the budget, a step at resolution R_k
  costing host + kernels (R_k / R_1)^COST_EXPONENT, times :func:`step_factor` at a whole-voxel step
  (:class:`StepCost`; measured: the kernels cost a
  step's samples, proportional to R, and its vertices, to R^2 on surfaces; the host's part is fixed
  per step, nothing on a CPU, most of a step on a GPU), with the kernels' seconds timed or costed in
  the coarse stage, leaving
  ``RESERVED`` of the budget to the background refit, the spherical-harmonic trials and the evaluation
  where a background is refitted, and ``RESERVED_NO_BACKGROUND`` to the trials and the evaluation alone
  where none is (no masks): the full field of such a capture takes the rest (:func:`reserved`);
* the default budget (``minutes`` 'auto', :func:`auto_minutes`) is costed at a reference speed, not
  timed: a coarse step takes its evaluated samples (counted in the calibration steps, which depend on
  the capture alone) over ``reference_msps``, the kernels' speed on the backend's reference machine,
  plus ``host_ms`` (:data:`BACKENDS`: the project's 2-core machine for llvm, an H200 for cuda; the
  budget, the batch and the memory bound follow the backend too). A capture so gets the same grid and
  steps on every machine of a backend, loaded or idle, fast or slow, and a resumed fit ends where an
  uninterrupted one would; the fit then runs at least ``min_steps`` steps (a small capture's budget
  buys fewer: the extra steps go to the grid the budget picked, as a grid seen too few times stays
  hazy, not to a finer one). Its last stage is costed again every ``REPLAN_EVERY`` steps from its
  100th on, from what its steps count: their samples (after the strides, the occupancy) and the stored
  floats they step, at the backend's reference rates (:func:`counted_step_seconds`,
  :func:`last_stage_steps`; :func:`mi_voldis.fit.train.recount`), as the coarse stage's model cannot
  know how many samples the strides save or how many vertices the carve keeps. A capture past the
  backend's bound of minutes gets more (:func:`auto_minutes`), which buy steps on the grid the bound's
  budget picks, not a finer one, at every stage: its stages are placed over ``min_steps`` times its
  minutes over the bound's at least, and the count sets the end (:func:`mi_voldis.fit.train.stage_floor`);
* a budget given in minutes is this machine's wall clock: the seconds per step are timed, and at the
  start of every later stage and every ``REPLAN_EVERY`` steps the steps still to come are rescaled to
  the budget that is left (:func:`rescale`), with the seconds a step took in the stage just finished or
  running: the cost model only has to be right one stage ahead, and within the last stage not at all,
  so the fit ends on time on any machine and scene.
"""
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

COST_EXPONENT = 1.25
RESERVED = 0.2
# without a background refit only the spherical-harmonic trials (sh_trial_steps steps of each degree) and the
# held-out evaluation follow the full phase: a few seconds of a budget of minutes
RESERVED_NO_BACKGROUND = 0.05


@dataclass(frozen=True)
class Backend:
    """What the default plan assumes of a Dr.Jit backend: the coarse stage's kernel speed (M samples/s)
    and the host's fixed milliseconds per step (:class:`StepCost`); the seconds a step of the last stage
    takes per evaluated training sample and per stored float of the fields it steps (ns,
    :func:`counted_step_seconds`); the budget per million training pixels and its bounds (minutes), the
    bound growing past ``growth_mpx`` million pixels (None: never) up to ``max_minutes``
    (:func:`auto_minutes`); the rays of a step and the memory a fit may take (GiB)."""
    reference_msps: float
    host_ms: float
    sample_ns: float
    float_ns: float
    minutes_per_mpx: float
    minutes: tuple
    growth_mpx: float | None
    max_minutes: float
    batch_rays: int
    max_memory_gib: float


# llvm: the project's 2-core machine, idle (the 64^3 calibration steps: tabletop 18.4, random 4 17.9, fern 16.4,
# statue 18.2, garden 20.0, horns 14.7 M samples/s; reports/notes.md), where the kernels are the step; 4 GiB of
# RAM (issue #42's bound). Its last stages: a step's seconds over its samples S and the floats F it steps, fitted
# (least squares of the relative error) to the captures' default fits timed alone, two runs of each of fern,
# horns, the statue and garden (0.40-0.94 M samples, 35-53 M floats a step), where a step's seconds are its share of
# the whole full phase: the phase's wall seconds, less what the plan gave the stages before the last, over the
# last stage's steps. So the TV's steps, the occupancy updates, the held-out evaluations, the checkpoints and
# the earlier stages' departures from their model are all priced in the steps the count buys; the fitted rates
# are then scaled until no fit's step is costed below what it took (the dearest: fern's slower run, 1.17x the
# fitted rates), so that their plans end within their budgets in the slower hours of a shared machine, early
# rather than late (reports/notes.md, "The plan's rates from whole fits"). Captures past 12 M training pixels
# (garden: 42 M) get more than 10 minutes, as issue #42's time targets do (10 minutes for fern, horns and the
# statue, 3-10 M pixels, 15 for garden). cuda: one H200
# (reports/gpu.md): a fit's step took 4.9-5.1 ms plus 1.0-1.1 ms per million samples, fern, the statue and
# garden alike, from 1 M to 4 M samples a step, so its host's share is fixed and its kernels run about 1000 M
# samples/s, its vertices not apart from them; 32 GiB of the card's memory (an H100 has 80); its budget's
# bound not grown (no GPU has run a capture past 12 M pixels under it).
BACKENDS = {
    "llvm": Backend(reference_msps=18.0, host_ms=0.0, sample_ns=175.4, float_ns=2.162, minutes_per_mpx=2.5,
                    minutes=(1.5, 10.0), growth_mpx=12.0, max_minutes=15.0, batch_rays=8192, max_memory_gib=4.0),
    "cuda": Backend(reference_msps=1000.0, host_ms=5.0, sample_ns=1.05, float_ns=0.0, minutes_per_mpx=0.5,
                    minutes=(1.0, 5.0), growth_mpx=None, max_minutes=5.0, batch_rays=32768, max_memory_gib=32.0),
}


# The sample spacing of a fit's stages after the coarse one (``step_voxels`` 'auto', :func:`choose_step`): half a
# voxel, or a whole one where the cheaper step buys steps on the grid memory bounds rather than a finer grid. The
# coarse stage marches at half a voxel: it is timed or costed for the plan, and its grid is coarse anyway.
HALF_VOXEL, WHOLE_VOXEL = 0.5, 1.0
# The share of a training step's kernels that marches the samples at the final stages, at half a voxel: the
# rest goes over the stored vertices (gradients, Adam, TV) and does not shrink with the step. The statue's
# explicit plan at 464^3 run at half and one voxel: 0.162 and 0.115 s a step (a share of 0.59); fern's default
# plan at 528^3: 0.75 of the seconds at one voxel (0.5; reports/notes.md, "A whole-voxel step where memory
# bounds the grid"). The lower share: a plan that overestimates a step ends early rather than late.
SAMPLE_SHARE = 0.5


def step_factor(step_voxels):
    """A training step's kernels at ``step_voxels`` over theirs at half a voxel: the samples' share
    SAMPLE_SHARE scales with the number of samples, 0.5 / step_voxels, the vertices' share does not."""
    return (1.0 - SAMPLE_SHARE) + SAMPLE_SHARE * HALF_VOXEL / float(step_voxels)


@dataclass(frozen=True)
class StepCost:
    """Seconds of a training step at resolution R:

        host + kernels (R / resolution)^COST_EXPONENT f,   f = ``fine`` where R > resolution, else 1

    ``kernels``: the seconds of a step's kernels at ``resolution`` (they grow with its samples and
    vertices); ``host``: what a step costs whatever its size (tracing, launches, the loss read back), the
    whole step on a GPU at small batches and nothing on a CPU; ``fine``: the kernels' factor at the finer
    stages where they march another step than the stage timed or costed (:func:`step_factor`)."""
    kernels: float
    resolution: int
    host: float = 0.0
    fine: float = 1.0

    def at(self, resolution):
        r = np.asarray(resolution, np.float64)
        factor = np.where(r > self.resolution, self.fine, 1.0)
        return self.host + self.kernels * (r / self.resolution) ** COST_EXPONENT * factor

    def marching(self, step_voxels):
        """This cost (at half a voxel) with the finer stages marching ``step_voxels``."""
        return StepCost(self.kernels, self.resolution, self.host, step_factor(step_voxels))

    @classmethod
    def timed(cls, seconds, resolution, host=0.0):
        """The cost of a step timed at ``seconds`` at ``resolution``: what is not the host's is the
        kernels' (a tenth of the step at least, should the host's estimate exceed the step)."""
        return cls(max(seconds - host, 0.1 * seconds), resolution, min(host, 0.9 * seconds))


def backend():
    """The backend of the Mitsuba variant in use: 'cuda' or 'llvm' (scalar variants cannot fit)."""
    return "cuda" if mi.variant().startswith("cuda") else "llvm"


def reserved(background):
    """The share of the budget left after the full phase: ``RESERVED`` where a background is refitted
    after it (``background``), else ``RESERVED_NO_BACKGROUND``."""
    return RESERVED if background else RESERVED_NO_BACKGROUND


def auto_minutes(dataset, which="llvm", grow=True):
    """Default budget of a dataset on backend ``which``: its minutes per million training pixels, within
    its bounds (llvm: 2.5, between 1.5 and 10), with ``grow`` the upper bound grown as the cube root of the
    pixels past ``growth_mpx`` million, at most ``max_minutes`` (llvm: 10 (P / 12)^(1/3), at most 15). The
    minutes past the bound buy steps, not a finer grid (:func:`mi_voldis.fit.train.plan_schedule` picks
    the grid with ``grow`` false)."""
    b = BACKENDS[which]
    pixels = len(dataset.train) * dataset.size[0] * dataset.size[1] / 1e6
    high = b.minutes[1]
    if grow and b.growth_mpx is not None and pixels > b.growth_mpx:
        high = min(b.max_minutes, high * (pixels / b.growth_mpx) ** (1 / 3))
    return float(np.clip(b.minutes_per_mpx * pixels, b.minutes[0], high))


def capture_survey(inputs, integrator, state, rays=1 << 16):
    """What the capture asks of the grid, from the current (coarse) fit's depths on ``rays`` training rays
    at pixel centres: {"capture_resolution": vertices along the scene box's longest side for which a
    voxel is ``pixels_per_voxel`` pixels wide in scene space where training rays end (the 25th percentile
    of the footprints, the finer views winning), rounded up to a multiple of 16, or None where no ray
    ends; "surface_cells": the cells of the current grid in which training rays end
    (:func:`surface_cells`), on the grid of "surface_resolution"; "ray_hits": the fraction of rays that
    end in one}."""
    from ..render.rays import render_rays
    cfg, bank, space = inputs.cfg, inputs.bank, inputs.space
    rng = np.random.default_rng([cfg.seed, 97])
    idx = np.sort(rng.choice(bank.pixels, min(rays, bank.pixels), replace=False)).astype(np.uint32)
    o, d, _, _, view = bank.rays(idx, np.full((len(idx), 2), 0.5, np.float32))
    with dr.suspend_grad():
        out = render_rays(integrator, o, d, dr.full(mi.Float, 0.5, len(idx)), ("full",))
    alpha, depth = np.array(out["full"][1]), np.array(out["full"][2])
    keep = alpha > 0.5
    if not keep.any():
        return {"capture_resolution": None, "surface_cells": None, "ray_hits": 0.0}
    focal = np.array([c.focal for c in bank.cams])[np.array(view)]
    o, d = np.array(o).T[keep], np.array(d).T[keep]
    z = depth[keep]
    footprint = z / focal[keep] * cfg.pixels_per_voxel  # world width of a pixel (times the factor) there
    x = o + z[:, None] * d
    scale = scene_scale(space, x, d)
    voxel = np.percentile(footprint * scale, 25)
    extent = float(np.max(state.hi - state.lo))
    resolution = int(np.clip(16 * np.ceil((extent / voxel + 1) / 16), 32, cfg.max_resolution))
    current = max(state.fields["full"].shape)
    cell = extent / (current - 1)
    ends = np.floor((space.from_world_np(x) - state.lo) / cell).astype(np.int64)
    counts = np.unique(ends, axis=0, return_counts=True)[1]
    return {"capture_resolution": resolution, "surface_cells": surface_cells(counts),
            "ray_hits": float(keep.mean()), "surface_resolution": int(current)}


def surface_cells(counts):
    """Effective number of cells rays end in, from the ray ends counted per cell (``counts``): the inverse
    Simpson index 1 / sum_c p_c^2 of the cells' shares p_c, estimated without bias as
    N (N - 1) / sum_c n_c (n_c - 1). S cells hit alike give S; it does not grow with the number of rays
    drawn, as the count of distinct cells does where a few rays stray into a fog of cells."""
    n = np.asarray(counts, np.float64)
    total, pairs = n.sum(), np.sum(n * (n - 1))
    return float(total * (total - 1) / pairs) if pairs > 0 else float(total)


def scene_scale(space, x, d):
    """Scene-space length of a unit world length at world points ``x`` across the viewing directions
    ``d`` (NumPy (n, 3)): the mean over two directions perpendicular to d."""
    if space.is_world:
        return np.ones(len(x))
    a = np.cross(d, np.where(np.abs(d[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(d, a)
    eps = 1e-3 * np.linalg.norm(x, axis=1, keepdims=True) + 1e-6
    out = 0.0
    for t in (a, b):
        out = out + np.linalg.norm(space.from_world_np(x + eps * t) - space.from_world_np(x - eps * t), axis=1) / (
            2 * eps[:, 0])
    return out / 2


def stages(cfg, coarse, final):
    """[(fraction of the steps where the stage starts, resolution), ...]: ``coarse``, then ``final`` halved
    as often as stays well above ``coarse``, doubling up to ``final``, at most ``stages`` stages, starting
    at 0 and at the last of ``stage_starts`` (the last stage always at the last fraction)."""
    levels = [max(final, coarse)]
    while levels[0] // 2 >= 1.4 * coarse:
        levels.insert(0, levels[0] // 2)
    if levels[0] > coarse:
        levels.insert(0, coarse)
    if len(levels) > cfg.stages:  # too many doublings: keep the coarse stage and the finest ones
        levels = [coarse] + levels[len(levels) - cfg.stages + 1:]
    fractions = [float(f) for f in cfg.stage_starts]
    while len(fractions) < len(levels) - 1:  # more stages than fractions: halve the first gap
        fractions.insert(0, fractions[0] / 2)
    starts = [0.0] + (fractions[len(fractions) - len(levels) + 1:] if len(levels) > 1 else [])
    return list(zip(starts, levels))


# A fit's peak memory (measured in reports/notes.md): a base that grows with the training pixels (the photos as
# float32 and the ray bank's codes, 4 bytes a pixel (mi_voldis.raybank): about 400 MiB and 22 bytes a pixel; 30
# while the bank kept garden's undistorted photos as floats) and a share per
# stored vertex of the fitted fields at colour degree 0: the values, their Adam moments and gradient and the three
# arrays Adam's kernel writes beside them, the TV's neighbour table (24 bytes), and what Dr.Jit's allocator keeps
# of the step's temporaries: 227-231 bytes measured on fern, horns and the statue (464^3 to 528^3, 12-13 M
# vertices), 266 on garden (320^3, 9.8 M vertices, whose rays take the most samples); in bricks of 4, garden 228
# (416^3, 10.2 M) and the statue 265 (592^3, 13.0 M, its carve tightened). The state holds the values
# Adam made (no stale copy), and the cache is released once the TV's table is built. The full phase is the peak:
# the background refit after it holds the full field's values beside its own but steps the object's region alone
# (Adam's ``subsets``), and each phase starts with Dr.Jit's allocation cache released. A few percent above the
# worst:
BASE_BYTES = 400 * 2 ** 20
BYTES_PER_PIXEL = 22
BYTES_PER_VERTEX = 272
# Stored vertices per effective surface cell of the final grid, for the plan: fern 55-66 (416^3-528^3), horns
# 81-87 (432^3-544^3), the removal family 55-195, the statue 150, garden 286 in bricks of 8; the statue 72 at
# 552^3 and garden 194 at 416^3 in bricks of 4 (reports/notes.md, reports/experiments/2026-12-06d, -06i). The plan takes
# about the lowest: every stage then counts its own vertices before it allocates them
# (:func:`mi_voldis.fit.fields.fitting_resolution`) and stops at the finest resolution within the bound, and the
# steps it then has to spare go to that stage (:func:`rescale_after_cap`), so a guess too low costs neither memory
# nor time, where one too high keeps a capture on a coarser grid than its memory holds.
VERTICES_PER_SURFACE_CELL = 64
# Whether memory binds the grid is a different question (:func:`choose_step`): there a count too low would read
# a grid bound by memory as bound by the observations whenever the memory estimate improves. It takes the
# median of the counts above (55, 55, 66, 72, 81, 87, 150, 194, 195, 286).
TYPICAL_VERTICES_PER_SURFACE_CELL = 84


def memory_scale(sh_degree, grey=False, view=False):
    """How much more memory a vertex takes at colour ``sh_degree`` (0, 1 or 'auto', which starts at 0; grey
    view dependence where ``grey``, on a view lattice where ``view``: the bricks then keep degree 0's floats)
    than BYTES_PER_VERTEX, measured at degree 0: its packed floats over degree 0's (4; degree 1: 16, 8 grey).
    Measured on
    fern: 7.0 GiB of peak RSS at degree 1 and 336^3 against 1.7 GiB at degree 0 and 304^3, 3.3 times as much
    per vertex (reports/notes.md)."""
    from ..field.grid import packet_width
    from ..field.spec import color_channels
    degree = 0 if sh_degree == "auto" else int(sh_degree)
    if degree == 1 and grey and view:
        return 1.0
    return packet_width(1 + color_channels(degree, grey)) / packet_width(4)


# A training step's kernels with a 64^3 view lattice over the same step without one, as fits run it: the
# seconds a sample after the onset over those before, each fit alone on the machine, 1.095 (family13) and 1.051
# (family14) (reports/notes.md). The larger, rounded up: a plan that overestimates a step ends early
# rather than late. The benchmark's random fields (every brick allocated, every sample in one) give more, 1.29 at
# 128^3 and 1.14 at 256^3; at 1.3 the plans of fern, horns and the statue, whose observation and memory bounds
# tie, turned to half-voxel steps at twice the samples a ray (reports/notes.md).
VIEW_STEP_COST = 1.1


def degree_cost_scale(cfg, sh_degree, start=0.0):
    """A training step's kernels at colour ``sh_degree`` over degree 0's, averaged over the full phase's steps
    from the fraction ``start`` of them on. On a view lattice (:func:`view_lattice_vertices`) the steps from
    ``sh_view_from`` on cost VIEW_STEP_COST and those before it degree 0's (the lattice, all 0, is not read);
    else the vertices' floats over degree 0's (:func:`memory_scale`)."""
    if not view_lattice_vertices(cfg, sh_degree):
        return memory_scale(sh_degree, cfg.sh_color == "grey")
    onset = min(max(float(cfg.sh_view_from or 0.0), start), 1.0)
    return ((onset - start) + (1.0 - onset) * VIEW_STEP_COST) / (1.0 - start) if start < 1.0 else VIEW_STEP_COST


def view_lattice_vertices(cfg, sh_degree):
    """Vertices of the view lattice a field of ``sh_degree`` gets under ``cfg`` (grey degree 1 with
    ``sh_view_resolution``), at most: the resolution cubed; 0 without one."""
    if sh_degree == "auto" or int(sh_degree) != 1 or cfg.sh_color != "grey" or not cfg.sh_view_resolution:
        return 0
    return cfg.sh_view_resolution ** 3


def affordable_vertices(cfg, pixels, sh_degree):
    """Stored brick vertices a fit can hold within ``max_memory_gib``: what the base of ``pixels`` training
    pixels and a view lattice (its vertices at BYTES_PER_VERTEX each: 4 floats, as a degree-0 vertex) leave,
    at BYTES_PER_VERTEX memory_scale(``sh_degree``, ``sh_color``) bytes each (0 when nothing is left)."""
    view = view_lattice_vertices(cfg, sh_degree)
    free = cfg.max_memory_gib * 2 ** 30 - BASE_BYTES - BYTES_PER_PIXEL * pixels - BYTES_PER_VERTEX * view
    return max(0.0, free / (BYTES_PER_VERTEX * memory_scale(sh_degree, cfg.sh_color == "grey", view > 0)))


def memory_resolution(cfg, surface_cells, surface_resolution, coarse, sh_degree, pixels,
                      per_cell=VERTICES_PER_SURFACE_CELL):
    """The finest resolution R (a multiple of 16, at least ``coarse``) whose estimated vertices fit in
    :func:`affordable_vertices`: ``surface_cells`` (R / surface_resolution)^2 cells of ``per_cell``
    vertices each, but never more than the dense lattice's R^3 (surfaces counted on a
    coarse grid that fill much of it: garden in a contracted space whose inner cube holds only what the
    cameras look at had 49,797 effective cells at 64^3, an estimate of 7.8 M vertices at 80^3, where the
    whole lattice holds 0.51 M)."""
    cells = surface_cells * (coarse / surface_resolution) ** 2  # at the coarse resolution
    vertices = affordable_vertices(cfg, pixels, sh_degree)
    return max(_finest(coarse, (vertices / per_cell / cells) ** 0.5),
               _finest(coarse, vertices ** (1 / 3) / coarse))


def _finest(coarse, ratio):
    """The largest multiple of 16 at most ``coarse`` * ``ratio``, and at least ``coarse``."""
    return int(max(coarse, 16 * np.floor(coarse * ratio / 16)))


def resolution_bounds(cfg, cost, budget_seconds, survey, pixels):
    """The finest resolution R (a multiple of 16, at least the coarse one, ``cost.resolution``) each rule
    allows: {"observations": R whose last stage (its share of the budget, stage_starts[-1] to the end)
    still ends ``min_observations`` training rays in each cell where rays end, a step at R costing
    ``cost.at(R)`` (:class:`StepCost`) and surfaces holding ``surface_cells`` (R / surface_resolution)^2
    cells (``survey``: :func:`capture_survey`); "pixels": R whose surface cells are no more than the
    ``pixels`` training pixels that end on them over ``pixels_per_voxel``^2 (a cell no pixel ends in has
    nothing to fit); "memory": R whose estimated peak memory stays within ``max_memory_gib``
    (:func:`memory_resolution`, at the colour degree ``sh_degree`` asks)}. Rays, not passes over the
    pixels, are the currency: a capture with more views buys the same grid or a finer one.

        steps(R) = share budget / cost(R),   rays(R) = steps(R) batch hits
        rays(R) / (cells (R / R_s)^2) >= min_observations
        cells (R / R_s)^2 <= pixels hits / pixels_per_voxel^2
        min(cells (R / R_s)^2 VERTICES_PER_SURFACE_CELL, R^3) <= affordable_vertices
    """
    coarse = cost.resolution
    share = 1.0 - (cfg.stage_starts[-1] if cfg.stage_starts else 0.0)
    cells = survey["surface_cells"] * (coarse / survey["surface_resolution"]) ** 2  # at the coarse resolution
    grid = np.arange(16 * -(-coarse // 16), max(cfg.max_resolution, coarse) + 1, 16, dtype=np.float64)
    rays = share * budget_seconds / cost.at(grid) * cfg.batch_rays * survey["ray_hits"]
    seen = rays >= cells * (grid / coarse) ** 2 * cfg.min_observations  # fewer as R grows: the finest is the bound
    return {"observations": int(grid[seen].max()) if seen.any() else int(coarse),
            "pixels": _finest(coarse, (pixels * survey["ray_hits"] / cfg.pixels_per_voxel ** 2 / cells) ** 0.5),
            "memory": memory_resolution(cfg, survey["surface_cells"], survey["surface_resolution"], coarse,
                                        cfg.sh_degree, pixels)}


def affordable_resolution(cfg, cost, budget_seconds, survey, pixels):
    """The finest resolution all rules of :func:`resolution_bounds` allow."""
    return min(resolution_bounds(cfg, cost, budget_seconds, survey, pixels).values())


def choose_step(cfg, cost, budget_seconds, survey, pixels):
    """The sample spacing (voxels) of the stages after the coarse one for ``step_voxels`` 'auto':
    WHOLE_VOXEL where, costed at it (``cost``: at half a voxel, :meth:`StepCost.marching`), the finest
    resolution is still bound by the memory or the training pixels, not by the observations the budget
    buys: a cheaper step then buys more steps on the same grid (fern, horns: the same or better on half
    the samples, reports/notes.md). HALF_VOXEL where the observations bound it: there a cheaper step
    only buys a finer grid that each ray sees less of (the removal family's small scenes lost so). Where a
    rule ties with the observations, the cheaper step: the grid is then the same. Decided on the plan's
    memory estimate, not on a later cap: garden, planned at half a voxel and capped far below its plan,
    lost on 22 of 24 held-out views at a whole voxel from the cap (reports/notes.md). The memory estimate
    here counts TYPICAL_VERTICES_PER_SURFACE_CELL, not the plan's lowest count: with the lowest, fern, horns
    and the statue sat where memory and observations tie, and a truer bytes-a-pixel figure turned horns to
    half voxels at a coarser grid, 0.10 dB lower (reports/experiments/2026-12-06i)."""
    bounds = resolution_bounds(cfg, cost.marching(WHOLE_VOXEL), budget_seconds, survey, pixels)
    memory = memory_resolution(cfg, survey["surface_cells"], survey["surface_resolution"], cost.resolution,
                               cfg.sh_degree, pixels, per_cell=TYPICAL_VERTICES_PER_SURFACE_CELL)
    others = min(bounds["pixels"], memory)
    return WHOLE_VOXEL if bounds["observations"] >= others else HALF_VOXEL


def steps_for(plan_stages, cost, budget_seconds):
    """Steps whose cost fills ``budget_seconds``, a step at resolution R costing ``cost.at(R)``
    (:class:`StepCost`)."""
    shares = np.diff([f for f, _ in plan_stages] + [1.0])
    per_step = sum(share * cost.at(level) for share, (_, level) in zip(shares, plan_stages))
    return int(budget_seconds / per_step)


def schedule_of(plan_stages, steps, first):
    """[[step, resolution], ...] of the stages over ``steps`` steps, the second stage starting after
    step ``first`` at the earliest, starts strictly increasing."""
    out = [[0, plan_stages[0][1]]]
    for fraction, level in plan_stages[1:]:
        out.append([max(int(round(fraction * steps)), first + 1, out[-1][0] + 1), level])
    return out


REPLAN_EVERY = 100  # steps between rescalings within a stage (and at every stage start)


def _ahead(schedule, steps_full, step):
    """What is ahead of ``step``: the index of the stage holding it, and the resolutions and step counts of
    the rest of that stage and of the stages after it."""
    k = max(i for i, (start, _) in enumerate(schedule) if start <= step)
    starts = [step] + [start for start, _ in schedule[k + 1:]]
    levels = np.array([r for _, r in schedule[k:]], np.float64)
    return k, levels, np.diff(starts + [steps_full]).astype(np.float64)


def cost_ahead(schedule, steps_full, step, cost):
    """Seconds the steps from ``step`` to ``steps_full`` of ``schedule`` cost, a step at resolution R
    costing ``cost.at(R)`` (:class:`StepCost`)."""
    _, levels, lengths = _ahead(schedule, steps_full, step)
    return float(np.dot(lengths, cost.at(levels)))


def rescale(schedule, steps_full, step, cost, budget_left):
    """(schedule, steps_full) with the steps from ``step`` on stretched or shrunk in proportion so that
    their cost fills ``budget_left`` seconds, a step at resolution R costing ``cost.at(R)``
    (:class:`StepCost`, timed on the stage run last). What is ahead is the rest of the stage holding
    ``step`` and the stages after it; each keeps at least one step; the steps before ``step`` are
    unchanged."""
    k, levels, lengths = _ahead(schedule, steps_full, step)
    factor = max(budget_left, 0.0) / float(np.dot(lengths, cost.at(levels)))
    lengths = np.maximum(1, np.round(lengths * factor)).astype(int)
    new_starts = step + np.concatenate([[0], np.cumsum(lengths)[:-1]])
    ahead = [[int(s), r] for s, (_, r) in zip(new_starts[1:], schedule[k + 1:])]
    return schedule[:k + 1] + ahead, int(step + lengths.sum())


def rescale_after_cap(schedule, steps_full, step, cap, cost, budget):
    """(schedule, steps_full) once memory stops the stage starting at ``step`` and those after it at
    ``cap`` (:func:`capped`): the seconds the plan gave the steps ahead, at the resolutions it planned,
    now buy steps at the capped ones (:func:`rescale`), as far as the phase's ``budget`` (seconds, all
    its steps) goes: a plan held at ``min_steps`` over its budget gets no more steps, and none ever gets
    fewer. Costed with ``cost`` (the plan's reference cost, :func:`plan_cost`), it depends on the plan
    alone: a resumed fit caps and rescales where an uninterrupted one did."""
    spent = cost_ahead(schedule, steps_full, 0, cost) - cost_ahead(schedule, steps_full, step, cost)
    left = min(cost_ahead(schedule, steps_full, step, cost), budget - spent)
    out = capped(schedule, cap, step)
    ahead, end = rescale(out, steps_full, step, cost, left)
    return (ahead, end) if end > steps_full else (out, steps_full)


def counted_step_seconds(plan, samples, floats):
    """Seconds of a training step that evaluates ``samples`` samples and steps fields of ``floats`` stored
    floats, at the reference rates the default ``plan`` recorded (``host_ms``, ``sample_ns``, ``float_ns``:
    :data:`BACKENDS`):

        host + samples sample_ns + floats float_ns"""
    return plan.get("host_ms", 0.0) / 1e3 + (samples * plan["sample_ns"] + floats * plan["float_ns"]) * 1e-9


def last_stage_steps(step, seconds, budget_left, min_steps):
    """``steps_full`` of a plan whose last stage, from ``step`` on, takes ``seconds`` a step: as many as
    ``budget_left`` buys, at least ``min_steps`` in all and one more than ``step``."""
    return max(step + max(int(max(budget_left, 0.0) / seconds), 1), int(min_steps))


def plan_cost(plan, coarse):
    """The :class:`StepCost` a default plan (costed at the reference speed: ``plan`` holds
    ``coarse_step_seconds``, ``host_ms`` and the finer stages' ``step_voxels``, half a voxel in plans
    made before it was recorded) was made with, its coarse stage at ``coarse``; its kernels times
    ``kernel_scale`` once degree-1 colour was chosen (:func:`~mi_voldis.fit.train.cap_for_sh_degree`)."""
    host = plan.get("host_ms", 0.0) / 1e3
    kernels = (plan["coarse_step_seconds"] - host) * plan.get("kernel_scale", 1.0)
    return StepCost(kernels, coarse, host).marching(plan.get("step_voxels", HALF_VOXEL))


def capped(schedule, cap, step=0):
    """``schedule`` with the stages from ``step`` on at most ``cap``, a stage that would repeat the
    resolution before it dropped."""
    out = []
    for start, r in schedule:
        r = min(r, cap) if start >= step else r
        if not out or r != out[-1][1]:
            out.append([start, r])
    return out


def resolution_at(schedule, step):
    """The resolution ``schedule`` sets for ``step``."""
    res = schedule[0][1]
    for start, r in schedule:
        if step >= start:
            res = r
    return res


def coarse_resolution(cfg):
    return cfg.resolution_schedule[0][1] if cfg.resolution_schedule else cfg.coarse_resolution


def finest_resolution(cfg):
    """The resolution whose voxel is the unit of raw densities: the explicit schedule's last, else the cap."""
    return cfg.resolution_schedule[-1][1] if cfg.resolution_schedule else cfg.max_resolution
