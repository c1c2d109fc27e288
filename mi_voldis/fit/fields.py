"""The fields of a fit: what it reads (:class:`FitInputs`), how its fields start, are carved and refined
from one resolution to the next, and the integrator that renders them. Free functions of the inputs
and a :class:`~mi_voldis.fit.state.FitState`."""
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from ..data.scene_box import fitting_box
from ..data.types import Dataset
from ..field.spec import constant_field
from ..field.state import carve, density_raw_for_alpha, new_field, resample, resampled_vertices, shape_for, voxel_size
from ..raybank import RayBank
from ..render import march
from ..scene import build_integrator, integrator_properties
from ..space import SceneBox, SceneSpace
from ..transforms import apply_point
from .config import FitConfig
from .schedule import HALF_VOXEL, affordable_vertices, coarse_resolution, finest_resolution

# the share of traced rays cut short by the march's sample cap at which a fit refines no further (sample_bound)
SAMPLE_CUT_SHARE = 0.01
# steps from carve_weight to carve_weight_memory a stage that memory binds may tighten its carve in
CARVE_RUNGS = 3


@dataclass(frozen=True)
class FitInputs:
    """What a fit reads and never changes: the dataset, the settings, the scene box and space the fields
    live in, the training rays, the checkpoint file, whether to show progress, and (found as the background
    starts) the object's dark fringe beside its masks ((N, H, W) bool or None, :mod:`mi_voldis.fit.fringe`)."""
    ds: Dataset
    cfg: FitConfig
    box: SceneBox
    space: SceneSpace
    bank: RayBank
    checkpoint: str
    progress: bool = True
    fringe: np.ndarray | None = None

    @classmethod
    def of(cls, dataset, cfg, checkpoint, progress=True):
        box = fitting_box(dataset, cfg.space, cfg.contract_shell, cfg.contract_radius)
        return cls(dataset, cfg, box, SceneSpace.from_box(box), RayBank(dataset, dataset.train), checkpoint,
                   progress)


def cell_size(lo, hi, resolution):
    """Edge of a cubic voxel of a grid with ``resolution`` vertices along the longest side of [lo, hi]."""
    return float((hi - lo).max() / (resolution - 1))


def init_fields(inputs, state, roles, sh_degree):
    """Fields of ``roles`` at the schedule's first resolution, every voxel equally faintly opaque
    (``density_init_alpha`` per sample step), raw densities per voxel of the finest resolution
    (:func:`~mi_voldis.fit.schedule.finest_resolution`)."""
    cfg = inputs.cfg
    res = coarse_resolution(cfg)
    step = cell_size(state.lo, state.hi, res) * step_voxels(cfg, state)
    scale = 1.0 / cell_size(state.lo, state.hi, finest_resolution(cfg))
    raw = density_raw_for_alpha(cfg.density_init_alpha, step, scale)
    for r in roles:
        state.fields[r] = new_field(state.lo, state.hi, res, sh_degree, raw, scale, cfg.brick,
                                    grey=cfg.sh_color == "grey", sh_gate=cfg.sh_gate,
                                    view_resolution=cfg.sh_view_resolution)


def refine(inputs, state, integrator, roles, resolution, max_vertices=None, max_samples=None):
    """Carve the fields of ``roles`` to the bricks where training rays end (some sample of some ray gets
    weight ``carve_weight``; grown by a brick) and resample them onto a lattice of ``resolution``
    vertices along the box's longest side, or with ``max_vertices`` the finest one (in steps of 16, not
    below the current lattice) whose carved fields hold no more stored vertices together
    (:func:`fitting_resolution`), and with ``max_samples`` in curved (contracted) space no finer than
    :func:`sample_bound` allows.
    Where ``max_vertices`` would hold the lattice below ``resolution``, the carve tightens along
    :func:`carve_ladder` (up to ``carve_weight_memory``) to the loosest weight that lets it reach
    ``resolution``, or else the loosest that reaches the finest lattice any does: a stage that memory binds trades
    the faintest bricks for resolution, one that it does not keeps them all.
    Returns the resolution used, the bound that chose it where one did ('memory', 'samples', None), and the
    carve weight used (None without carving)."""
    cfg = inputs.cfg
    weights, evaluated = {}, []
    for r in roles:
        if cfg.carve:
            weights[r], counts = ray_weights(inputs, integrator, r)
            evaluated.append(counts)

    def keeps_at(threshold):
        if not cfg.carve:
            return {r: None for r in roles}
        keeps = {}
        for r in roles:
            needed = weights[r] > threshold
            if not needed.any():  # a field still nearly transparent everywhere: keep its strongest bricks
                top = weights[r].max()
                needed = weights[r] >= 0.5 * top if top > 0 else np.ones(weights[r].shape, bool)
            keeps[r] = carve(state.fields[r], needed)
        return keeps

    weight = cfg.carve_weight if cfg.carve else None
    keeps = keeps_at(weight)
    bound = None
    current = max(max(state.fields[r].shape) for r in roles)
    if max_samples is not None and evaluated and inputs.space.is_curved:
        limit = sample_bound(current, np.concatenate(evaluated), max_samples)
        if limit < resolution:
            resolution, bound = limit, "samples"
    if max_vertices is not None:
        used = fitting_resolution(state, keeps, resolution, max_vertices)
        for tighter in (carve_ladder(cfg) if cfg.carve else ())[1:]:
            if used >= resolution:
                break
            tight = keeps_at(tighter)
            reached = fitting_resolution(state, tight, resolution, max_vertices)
            if reached > used:
                used, keeps, weight = reached, tight, tighter
        resolution, bound = (used, "memory") if used < resolution else (resolution, bound)
    for r in roles:
        state.fields[r] = resample(state.fields[r], shape_for(state.lo, state.hi, resolution), keeps[r])
    dr.flush_malloc_cache()  # the coarser lattice's arrays, cached by Dr.Jit's allocator, are of no use now
    return resolution, bound, weight


def carve_ladder(cfg):
    """The carve weights a stage that memory binds may try, loosest first: ``carve_weight`` and then
    CARVE_RUNGS geometric steps up to ``carve_weight_memory`` (just ``carve_weight`` where that is not
    above it)."""
    lo, hi = cfg.carve_weight, cfg.carve_weight_memory
    if hi <= lo:
        return [lo]
    return [float(lo * (hi / lo) ** (k / CARVE_RUNGS)) for k in range(CARVE_RUNGS + 1)]


def sample_bound(current, evaluated, max_samples):
    """The finest resolution the rays traced now allow: the current one ``current`` where more than
    SAMPLE_CUT_SHARE of them already evaluate ``max_samples`` samples (``evaluated``: per ray, at the
    current grid), else no bound (a very large number). A curved ray stops after ``max_samples``
    evaluated samples, and a finer grid only adds samples (a step is ``step_voxels`` of its voxels): the
    rays through the most occupied cells would stop short of the surfaces behind them, and the fit would
    explain their pixels with the backdrop instead (straight rays spread their ``max_samples`` over their
    whole interval: they are not cut short). The share is measured, not projected from the grid's
    growth: as occupancy tightens, samples grow more slowly than the resolution (reports/gpu.md)."""
    if len(evaluated) and np.mean(np.asarray(evaluated) >= max_samples) > SAMPLE_CUT_SHARE:
        return current
    return np.iinfo(np.int32).max


def fitting_resolution(state, keeps, resolution, max_vertices):
    """The finest resolution R <= ``resolution`` (``resolution`` itself, or the current lattice's plus a
    multiple of 16) at which the fields of ``keeps`` (role -> carved bricks, None: all allocated),
    resampled, hold at most ``max_vertices`` stored vertices together; the current resolution where none
    does. Bisection: the count grows with R."""
    current = max(max(state.fields[r].shape) for r in keeps)

    def vertices(res):
        return sum(resampled_vertices(state.fields[r], shape_for(state.lo, state.hi, res), keep)
                   for r, keep in keeps.items())

    if resolution <= current or vertices(resolution) <= max_vertices:
        return resolution
    lo, hi = 0, (resolution - current - 1) // 16  # candidates current + 16 k, k in [1, hi]; lo: fits
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if vertices(current + 16 * mid) <= max_vertices:
            lo = mid
        else:
            hi = mid - 1
    return current + 16 * lo


def memory_bound(inputs, state):
    """The most stored vertices the fields being fitted may hold (:func:`~mi_voldis.fit.schedule.
    affordable_vertices`) where the plan chose the resolution (``resolution`` 'auto'), else None."""
    cfg = inputs.cfg
    if cfg.resolution != "auto" or cfg.resolution_schedule or not (state.plan or {}).get("surface_cells"):
        return None
    return affordable_vertices(cfg, inputs.bank.pixels, max(f.sh_degree for f in state.fields.values()))


def refits_background(inputs):
    """Whether a background is refitted after the full field (masks given, ``bg_strategy`` not 'scratch'):
    both fields then live at once."""
    return inputs.ds.masks is not None and inputs.cfg.bg_strategy != "scratch"


def ray_weights(inputs, integrator, role):
    """Per brick of the field of ``role`` (bz, by, bx NumPy): the largest weight that any traced training
    ray (``carve_rays`` of them, at pixel centres) gives a sample there; and the samples each of those
    rays evaluated (NumPy)."""
    field = integrator.fields[role]
    layout, to_local = field.layout, field.world_to_local
    bx, by, bz = layout.counts
    best = dr.zeros(mi.Float, bx * by * bz)
    plan = integrator.plan((role,))
    chain = plan.sources.full if role == "full" else plan.sources.bg
    res = mi.Vector3f(*[float(s - 1) for s in layout.shape])

    def probe(p, w, active, depth):
        v = mi.Vector3u(dr.clip(apply_point(to_local, p), 0.0, 1.0) * res + 0.5) // layout.brick
        dr.scatter_reduce(dr.ReduceOp.Max, best, w[chain], (v.z * by + v.y) * bx + v.x, active)

    bank = inputs.bank
    count = min(inputs.cfg.carve_rays, bank.pixels)
    pixels = np.random.default_rng([inputs.cfg.seed, 98]).choice(bank.pixels, count, replace=False)
    evaluated = []
    with dr.suspend_grad():
        for s in range(0, count, 1 << 17):
            idx = np.sort(pixels[s:s + (1 << 17)]).astype(np.uint32)
            o, d, *_ = bank.rays(idx, np.full((len(idx), 2), 0.5, np.float32))
            rays = march.prepare_rays(plan, o, d)
            fwd = march.forward(plan, rays, dr.full(mi.Float, 0.5, len(idx)), probe=probe)
            dr.eval(best, fwd.stats["evaluated"])
            evaluated.append(np.array(fwd.stats["evaluated"]))
    return np.array(best).reshape(bz, by, bx), np.concatenate(evaluated)


def occupancy_sigma(cfg, state):
    """Density (per scene unit) of a voxel of opacity ``occupancy_alpha`` at the current grid."""
    return -np.log1p(-cfg.occupancy_alpha) / voxel_size(state.fields["full"])


def occupancy_resolution(cfg, state, voxels=None):
    """Occupancy cells along the box's longest side: cells ``voxels`` (default ``occupancy_voxels``)
    voxels of the current grid across."""
    return max(1, int(np.ceil((max(state.fields["full"].shape) - 1) / (voxels or cfg.occupancy_voxels))))


def step_voxels(cfg, state):
    """Sample spacing along rays in voxels of the current grid: ``step_voxels`` where it is a number; for
    'auto', half a voxel on the coarse stage and what the plan chose for the stages after it
    (:func:`~mi_voldis.fit.schedule.choose_step`; half a voxel where no plan chose)."""
    if cfg.step_voxels != "auto":
        return float(cfg.step_voxels)
    fine = "full" in state.fields and max(state.fields["full"].shape) > coarse_resolution(cfg)
    return float((state.plan or {}).get("step_voxels", HALF_VOXEL)) if fine else HALF_VOXEL


def sample_step(cfg, state):
    """Sample spacing along rays (scene units): :func:`step_voxels` of the current grid's voxels."""
    return step_voxels(cfg, state) * voxel_size(state.fields["full"])


def scene_properties(inputs, state, **options):
    """Integrator properties of the fitted scene (space, samples, step, near) plus ``options``."""
    return integrator_properties(inputs.space, samples=inputs.cfg.max_samples, near=float(inputs.box.near),
                                 step_size=float(sample_step(inputs.cfg, state)), **options)


def fit_integrator(inputs, state, properties=None):
    """The ``voldis`` integrator over the current fields with ``properties`` (default
    :func:`scene_properties` with fitting's strides (:func:`fit_strides`): no occupancy, fitting updates it itself)."""
    full = state.fields["full"]
    bg = state.fields.get("bg")
    # the full phase of "refit": an empty stand-in background over the same box
    bg = bg.plugin() if bg is not None else constant_field(1e-12, (0.0, 0.0, 0.0), full.to_world)
    strides = curved_strides(inputs, fit_strides(inputs, state))
    properties = properties or scene_properties(inputs, state, strides=strides)
    return build_integrator({"full": full.plugin(), "bg": bg}, properties)


def fit_strides(inputs, state):
    """Whether fitting strides now (``strides``): at every stage, or from the planned last one on."""
    which = inputs.cfg.strides
    last = state.steps_full is not None and max(state.fields["full"].shape) >= state.schedule[-1][1]
    return which == "all" or (which == "last" and last)


def curved_strides(inputs, on):
    """The integrator's ``strides`` property for a setting ``on``: only contracted space has them."""
    return bool(on and inputs.space.is_curved) or None


def scene_integrator(inputs, state):
    """The integrator a finished fit's ``scene.xml`` describes, so that what is scored is what the run
    renders: :func:`fit_integrator` with the scene's own rules (:func:`fitted_scene_properties`), whose
    skipped cells and earlier stop change the render (a faint haze left out). Returns (integrator, its
    properties)."""
    props = fitted_scene_properties(inputs, state)
    integrator = fit_integrator(inputs, state, props)
    return integrator, props


def fitted_scene_properties(inputs, state):
    """Integrator properties of the fitted scene: :func:`scene_properties` with occupancy cells
    ``scene_occupancy_voxels`` voxels across at the threshold :func:`occupancy_sigma` (none without
    ``occupancy_at_step``), rays stopped at ``scene_stop_transmittance`` and, in contracted space with
    ``scene_strides``, longer steps through thin cells."""
    cfg = inputs.cfg
    cells = occupancy_resolution(cfg, state, cfg.scene_occupancy_voxels) if cfg.occupancy_at_step else 0
    return scene_properties(inputs, state, occupancy_resolution=cells,
                            occupancy_threshold=float(occupancy_sigma(cfg, state)),
                            stop_transmittance=float(cfg.scene_stop_transmittance),
                            strides=curved_strides(inputs, cfg.scene_strides))
