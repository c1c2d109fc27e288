"""Fit the full-scene and background radiance fields of a dataset (paper Sec. 3.1).

    L_full = sum_i ||x_i - x^_i||^2 over all pixels,   L_bg = sum_i ||(1 - m_i)(x_i - x^_i)||^2

(:func:`mi_voldis.losses.full_loss`, :func:`mi_voldis.losses.background_loss`), both through the
``voldis`` integrator's renders (same sampler, quadrature and mixing as every later task) and Dr.Jit's
reverse-mode AD, with Adam on raw voxel grids.

Phases (``bg_strategy``):

* ``harmonic``: fit the full field; the background starts as a copy of it with the object's
  visual hull (from the masks) filled with the harmonic extension of the field around it, the
  object's own voxels (unseen unmasked, and dense where a masked ray can show them or, with
  ``object_front``, just before them on a masked ray) emptied
  (:func:`~mi_voldis.fit.background.start_harmonic`), and only hull cells are refitted with L_bg on
  rays near the masks. Outside the hull the two fields' densities are identical, so on a ray the
  foreground w_full - w_bg is exactly zero until it reaches the hull; with ``keep_seen`` (default) the
  hull voxels some training view sees unmasked keep the full field's density too (their colour is
  refitted), except within ``keep_seen_gap`` vertices of the object's voxels (its soft edge); with
  ``hull_color_fill`` the filled voxels' colour comes from outside the hull alone.
* ``guided`` (default): ``harmonic``, and the refit adds a 2D colour prior on the masked rays of every masked
  training view (each view's photo inpainted in its mask, occluders in front of the object left out of
  the inpainting's sources; weight ``prior_weight`` against 1 for L_bg, :mod:`mi_voldis.fit.guide`):
  what no view sees becomes the views' consensus instead of the harmonic fill's blend. With effect masks
  (the dataset's ``effects``: the object's shadow on the rest of the scene; without them, the shadow
  found from the object's shape and the photos, :mod:`mi_voldis.fit.shadow`), and the object's dark fringe
  beside its masks (its contact shadow and dark soft edge, :mod:`mi_voldis.fit.fringe`), their pixels leave
  L_bg and join the prior's, and the surfaces under them are refitted in colour alone
  (:func:`~mi_voldis.fit.background.effect_cells`): the shadow leaves with the object, the floor stays.
* ``lift``: the same full field; the background starts as a copy of it with the part of the object's
  visual hull (from the masks) no training view sees unmasked emptied, only hull cells are refitted
  with L_bg on rays near the masks (what other views see), and what no view sees is filled from a
  reference view's 2D inpainting lifted into 3D (:mod:`mi_voldis.fit.lift`), after emptying what only
  the object can occupy.
* ``clear``: the hull's unseen part emptied and the hull refitted, without the prior (the paper's masked loss alone).
* ``scratch``: both fields from scratch, jointly, on the same rays (two layers of one march).

Where the background has no density its colour is unconstrained, yet c_fg = c_full - c_bg reads it;
after fitting, background colour is set to black wherever its voxel opacity is negligible, so that
there c_fg = c_full (``empty_color_alpha``).
"""
import dataclasses
import sys
import time

import drjit as dr
import numpy as np

from .. import exposure
from ..data import check_rig
from ..field.state import neighbour_vertices
from ..inpaint2d import fallback_note
from ..inpaint2d import inpainter as get_inpainter
from ..metrics import psnr
from ..optim.adam import Adam
from ..optim.loop import optimize
from ..raybank import RayBank
from ..render.views import render_camera
from .background import (
    background_ray_pool,
    background_regions,
    clear_empty_background_color,
    effect_cells,
    hull_region,
    no_denser,
    start_cleared,
    start_harmonic,
)
from .fields import FitInputs, fit_integrator, init_fields, refits_background
from .fringe import find_fringe
from .guide import colour_prior, view_depth
from .hull import check_hull
from .lift import keys_mask, lift_prior
from .problem import FieldFit
from .schedule import (
    REPLAN_EVERY,
    StepCost,
    auto_minutes,
    backend,
    capped,
    capture_survey,
    choose_step,
    coarse_resolution,
    cost_ahead,
    counted_step_seconds,
    degree_cost_scale,
    last_stage_steps,
    memory_resolution,
    plan_cost,
    rescale,
    reserved,
    resolution_bounds,
    schedule_of,
    stages,
    steps_for,
    view_lattice_vertices,
)
from .sh_degree import choose_sh_degree
from .shadow import find_shadow
from .state import FitState


def fit(dataset, checkpoint, cfg, resume=False, progress=True, inpainter=None):
    """Fit ``dataset``, checkpointing to the file ``checkpoint``. Returns the inputs and the final
    :class:`FitState` (fields, log, phase times). ``inpainter``: a 2D inpainter callable for the ``guided``
    and ``lift`` priors (:mod:`mi_voldis.inpaint2d`), instead of the one ``cfg.prior_inpainter`` names."""
    cfg = cfg.for_backend(backend())
    check_rig(dataset)  # cameras at one point: nothing to fit depth from
    inputs = FitInputs.of(dataset, cfg, checkpoint, progress)
    adam = Adam({}, cfg.adam_beta1, cfg.adam_beta2, warmup=cfg.lr_warmup)
    state = FitState.load(checkpoint, adam) if resume else None
    if resume and state is None:
        raise ValueError(f"{checkpoint}: no checkpoint to resume from")
    has_masks = dataset.masks is not None
    if has_masks and cfg.bg_strategy in ("guided", "lift"):  # fail now, not after the full phase
        check_inpainter(inpainter or cfg.prior_inpainter, progress)
    scratch = cfg.bg_strategy == "scratch" and has_masks
    if has_masks and not scratch:  # an empty object hull fails now, not after the full phase
        check_hull(inputs)
    roles = ("full", "bg") if scratch else ("full",)
    if state is None:
        state = FitState(np.asarray(inputs.box.lo, np.float64), np.asarray(inputs.box.hi, np.float64), adam)
        if cfg.exposure:
            state.exposure = exposure.identity(len(dataset.train))
        init_fields(inputs, state, roles, 0 if cfg.sh_degree in ("auto", 0) else int(cfg.sh_degree))

    def checkpoint_at(phase):
        def saver(problem):
            def save(step):
                problem.sync_states()  # the optimised values live in the problem's integrator until synced
                state.save(checkpoint, phase, step)
            return save
        return saver

    if state.phase == "full":
        fit_full(inputs, state, roles, scratch, checkpoint_at("full"))
        state.adam.reset()
        state.save(checkpoint, "bg", 0)
        dr.flush_malloc_cache()  # the full phase's arrays, cached by Dr.Jit's allocator: the refit's differ in size

    if state.phase == "bg" and has_masks and not scratch:
        t0 = time.perf_counter()
        harmonic = cfg.bg_strategy in ("harmonic", "guided")
        regions = None
        depths = {}  # the full field's median depth maps by view: its regions, shadow and prior each ask for them
        if cfg.bg_strategy == "guided" and cfg.fringe_contrast > 0:  # its contact shadow and dark soft edge
            inputs = dataclasses.replace(inputs, fringe=object_fringe(inputs, state, depths, progress))
        if "bg" not in state.fields or state.hull_points is None:
            if harmonic:
                regions = start_harmonic(inputs, state, depths)
            else:
                state.prior_keys = start_cleared(inputs, state)
                state.prior = {"vertices_emptied": int(len(state.prior_keys))}
            if cfg.bg_strategy == "lift":
                lifted, keys = lift_prior(inputs, state, lambda f: hull_region(inputs, f, neighbour_vertices(f))[0],
                                          cfg.prior_views, fill=inpainter or cfg.prior_inpainter)
                state.prior.update(lifted)
                state.prior_keys = np.union1d(state.prior_keys, keys)
        shaped = None  # where the density may change, if not wherever the colour may
        if harmonic:  # the object's own voxels stay empty
            if regions is None:
                hull, _, obj, refill, through = background_regions(inputs, state, depths=depths, with_through=True)
            else:
                hull, obj, refill, through = regions
            free = dr.select(obj, 0.0, hull)
            if cfg.keep_seen:  # what some view sees keeps the full field's density
                shaped = dr.select(refill, free, 0.0)
        else:  # on the background's lattice (the lifted prior may have allocated bricks)
            free = cleared_region(inputs, state)
        effects = dataset.effects if cfg.bg_strategy == "guided" else None
        if effects is None and cfg.bg_strategy == "guided" and cfg.shadow_contrast > 0:
            effects, light = find_shadow(inputs, state, depths=depths)  # the object's shadow, from its shape
            state.prior = {**(state.prior or {}), "shadow": light}
            if effects is not None:
                inputs = dataclasses.replace(inputs, ds=dataclasses.replace(dataset, effects=effects))
                if progress:
                    print(f"note: the object's shadow found ({100 * (1 - np.exp(-light['contrast'])):.0f}% darker "
                          f"than beside it, light at {np.round(light['light'], 2).tolist()}): it leaves with the "
                          "object (--set shadow_contrast=0 keeps it)", file=sys.stderr)
        if inputs.fringe is not None:  # the object's fringe leaves with it as its shadow does
            effects = inputs.fringe if effects is None else effects | inputs.fringe
            inputs = dataclasses.replace(inputs, ds=dataclasses.replace(dataset, effects=effects))
        if effects is not None:  # the surfaces under the object's shadow: their colour alone is refitted
            shaped = free if shaped is None else shaped
            free = dr.select(effect_cells(inputs, state), 1.0, free)
        pool = background_ray_pool(dataset, inputs.bank, cfg.bg_ray_dilation, effects)
        prior = (colour_prior(inputs, state, inpainter or cfg.prior_inpainter, depths=depths)
                 if cfg.bg_strategy == "guided" and cfg.prior_weight > 0 else None)
        dr.flush_malloc_cache()  # what the regions, the shadow search and the prior left cached
        problem = FieldFit(inputs, state, ("bg",), ("bg",), inputs.bank, pool=pool, hull=free, phase=1,
                           schedule=False, prior=prior, density_hull=shaped, rates=(cfg.bg_lr_density, cfg.bg_lr_color),
                           tv=(cfg.bg_tv_density, cfg.bg_tv_color))
        optimize(problem, state.adam, steps=cfg.steps_bg, start=state.step, final_ratio=cfg.lr_final_ratio,
                 log=state.log, desc="bg refit", checkpoint=checkpoint_at("bg")(problem),
                 **checkpoints(cfg), progress=progress)
        problem.sync_states()
        if harmonic and dr.count(through)[0] > 0:  # the haze views see through: cleared at most, never thickened
            state.fields["bg"] = no_denser(state.fields["bg"], state.fields["full"], through)
        state.phase_times["bg"] = state.phase_times.get("bg", 0.0) + time.perf_counter() - t0
    if "bg" not in state.fields:  # no masks: nothing to disentangle, the background is the full scene
        full = state.fields["full"]
        state.fields["bg"] = full.with_data(full.data)
    if has_masks:
        cleared = cleared_region(inputs, state) > 0 if cfg.bg_strategy in ("clear", "lift") else None
        state.empty_color_fraction = clear_empty_background_color(inputs, state, cleared)
    dr.flush_malloc_cache()  # the checkpoint, the evaluation and the export that follow allocate arrays of other sizes
    state.save(checkpoint, "done", 0)
    return inputs, state


def object_fringe(inputs, state, depths, progress):
    """The object's dark fringe beside its masks ((N, H, W) bool, :mod:`mi_voldis.fit.fringe`; None where none
    is found), recorded in ``state.prior['fringe']``; ``depths``: the full field's median depth maps by view,
    read and filled."""
    ds, cfg = inputs.ds, inputs.cfg
    integrator = fit_integrator(inputs, state)
    for v in ds.masked_train:
        view_depth(integrator, ds, v, depths)
    fringe = find_fringe(ds, cfg.fringe_width, cfg.fringe_contrast, depths)
    found = 0 if fringe is None else int(fringe.sum())
    record = {"pixels": found, "views": 0 if fringe is None else int(fringe.any(axis=(1, 2)).sum())}
    state.prior = {**(state.prior or {}), "fringe": record}
    if fringe is not None and progress:
        print(f"note: the object's dark fringe found beside its masks ({found} pixels in {record['views']} views: "
              "its contact shadow, its dark edge): it leaves with the object (--set fringe_contrast=0 keeps it)",
              file=sys.stderr)
    return fringe


def check_inpainter(fill, progress=True):
    """Run the 2D inpainter ``fill`` (a name or a callable) on a tiny image: raises what it would raise
    in the background phase (e.g. a missing library) before any fitting. With ``progress``, a note says
    which inpainter 'auto' uses where it cannot use 'fsr'."""
    note = fallback_note(fill) if isinstance(fill, str) else None
    if note and progress:
        print(f"note: {note}", file=sys.stderr)
    image, hole = np.full((8, 8, 3), 0.5, np.float32), np.zeros((8, 8), bool)
    hole[3:5, 3:5] = True
    get_inpainter(fill)(image, hole)


def cleared_region(inputs, state):
    """Float per stored background vertex, 1 where ``clear`` / ``lift`` changed the background: the
    object's hull (on the background's lattice: the lifted prior may have allocated bricks) and the
    vertices the prior emptied or wrote."""
    bg = state.fields["bg"]
    hull = hull_region(inputs, bg, neighbour_vertices(bg))[0]
    if state.prior_keys is None or not len(state.prior_keys):
        return hull
    return dr.select(keys_mask(bg, state.prior_keys), 1.0, hull)


def fit_full(inputs, state, roles, scratch, checkpoint):
    """The full-scene phase (with the background too for ``scratch``), from ``state.step``: the coarse
    stage's first ``calibration_steps`` at a constant learning rate when the schedule is still to be
    planned (:mod:`mi_voldis.fit.schedule`), then the planned stages with a decaying rate; with
    ``sh_degree`` 'auto' the degree is chosen once the coarse geometry stands (the first refinement).
    ``checkpoint(problem)``: the function that saves a step of ``problem``."""
    cfg = inputs.cfg
    t0 = time.perf_counter()
    if state.schedule is None and cfg.resolution_schedule and cfg.steps_full:
        state.schedule, state.steps_full = cfg.resolution_schedule, cfg.steps_full
    if state.schedule is None:
        state.schedule = [[0, coarse_resolution(cfg)]]  # the coarse stage, until planned
    problem = FieldFit(inputs, state, roles, roles, inputs.bank, fit_exposure=True, view_rates=True,
                       view_dependence_late=True, average=True)
    problem.on_stage = lambda step: replan(state, step)
    eval_fn = held_out_psnr(inputs, problem)
    common = dict(log=state.log, checkpoint=checkpoint(problem), **checkpoints(cfg), eval_fn=eval_fn,
                  eval_every=cfg.eval_every, progress=inputs.progress)
    if state.steps_full is None:
        optimize(problem, state.adam, steps=cfg.calibration_steps, start=state.step, final_ratio=1.0,
                 desc="full (calibration)", **common)
        problem.sync_states()
        plan_schedule(inputs, state, problem.integrator)
        state.save(inputs.checkpoint, "full", cfg.calibration_steps)
        if inputs.progress:
            print(f"plan: {describe_plan(state)}", file=sys.stderr)
    start = state.step
    sh_step = state.schedule[1][0] if len(state.schedule) > 1 else state.steps_full // 3
    if cfg.sh_degree == "auto" and start < sh_step:
        optimize(problem, state.adam, steps=sh_step, start=start,
                 final_ratio=cfg.lr_final_ratio ** (sh_step / state.steps_full), desc="full (coarse)", **common)
        problem.sync_states()
        if choose_sh_degree(inputs, state, roles):
            cap_for_sh_degree(inputs, state, 1, sh_step)
        c = state.sh_choice
        if inputs.progress and "val_psnr_degree0" in c:
            print(f"note: colour of SH degree {c['degree']} (the trial fits' validation views: "
                  f"{c['val_psnr_degree1'] - c['val_psnr_degree0']:+.2f} dB at degree 1; sh_gain_db "
                  f"{cfg.sh_gain_db})", file=sys.stderr)
        state.adam.reset()
        problem.rebuild()
        start = sh_step
    optimize(problem, state.adam, steps=lambda: state.steps_full, start=start, final_ratio=cfg.lr_final_ratio,
             desc="full" if not scratch else "full + bg", **common)
    problem.sync_states()
    problem.take_averages()
    state.phase_times["full"] = state.phase_times.get("full", 0.0) + time.perf_counter() - t0


def checkpoints(cfg):
    """When :func:`~mi_voldis.optim.loop.optimize` checkpoints: every ``checkpoint_every`` steps where set,
    else every ``checkpoint_minutes``."""
    if cfg.checkpoint_every is not None:
        return {"checkpoint_every": cfg.checkpoint_every}
    return {"checkpoint_seconds": 60.0 * cfg.checkpoint_minutes}


def cap_for_sh_degree(inputs, state, degree, step):
    """Degree-1 colour chosen at ``step`` after the plan (``sh_degree`` 'auto'), which was bounded in
    memory and costed at degree 0: stages finer than the memory bound at ``degree``
    (:func:`memory_resolution`) take that bound instead, a stage that would repeat the one before it is
    dropped, and the plan records the cap. The default plan (costed at the reference speed) then costs its
    steps at ``degree`` (:func:`~mi_voldis.fit.schedule.degree_cost_scale`: a step's kernels move vertices
    of more floats, or from ``sh_view_from`` on also read a view lattice), ``plan['kernel_scale']``, which
    :func:`plan_cost` applies from then on, and the seconds the plan gave the steps from ``step`` on buy that
    many fewer. A plan made at degree 1 on a view lattice records its scale from the start
    (:func:`plan_schedule`)."""
    cfg, plan = inputs.cfg, state.plan or {}
    if cfg.resolution != "auto" or "surface_cells" not in plan:
        return
    coarse = state.schedule[0][1]
    left = cost_ahead(state.schedule, state.steps_full, step, plan_cost(plan, coarse)) if "reference_msps" in plan \
        else None
    cap = memory_resolution(cfg, plan["surface_cells"], plan["surface_resolution"], coarse, degree, inputs.bank.pixels)
    if any(r > cap for _, r in state.schedule):
        state.schedule = capped(state.schedule, cap)
        plan["sh_memory_cap"] = cap
    if left is not None:
        plan["kernel_scale"] = degree_cost_scale(cfg, degree, step / state.steps_full)
        state.schedule, state.steps_full = rescale(state.schedule, state.steps_full, step, plan_cost(plan, coarse),
                                                   left)
        plan.setdefault("rescaled", []).append([step, state.steps_full])


def replan(state, step):
    """With a wall-clock budget (``minutes`` given), rescale the steps from ``step`` to the budget left
    (:func:`rescale`), timed on the stage just finished (at a stage start) or on the one running; the
    default plan (costed at the reference speed) has its last stage costed from what its steps count
    (:func:`recount`); explicit step counts stay."""
    plan = state.plan or {}
    budget = plan.get("budget_seconds")
    if budget is None or step >= state.steps_full:
        return
    if "reference_msps" in plan:
        recount(state, step)
        return
    k = max(i for i, (start, _) in enumerate(state.schedule) if start <= step)
    timed = k - 1 if state.schedule[k][0] == step else k  # the stage whose steps are timed
    if timed < 0:
        return
    end = state.schedule[timed + 1][0] if timed + 1 < len(state.schedule) else state.steps_full
    rows = [r["step_seconds"] for r in state.log if state.schedule[timed][0] < r["step"] <= min(step, end) and
            "step_seconds" in r and "test_psnr" not in r]
    rows = rows[len(rows) // 5:]  # past the stage's first steps (kernels compiling, occupancy starting)
    if len(rows) < 10:
        return
    cost = StepCost.timed(float(np.median(rows)), state.schedule[timed][1], plan.get("host_ms", 0.0) / 1e3)
    if timed == 0 and "step_voxels" in plan:  # timed at the coarse stage's half-voxel step, the finer stages
        cost = cost.marching(plan["step_voxels"])  # march the plan's
    state.schedule, state.steps_full = rescale(state.schedule, state.steps_full, step, cost,
                                               budget - state.log[-1]["time"])
    state.plan.setdefault("rescaled", []).append([step, state.steps_full])


def recount(state, step):
    """The default plan's last stage (after the coarse one, which the plan costed from its counted samples
    already) costed from what its steps count, at every replan from REPLAN_EVERY steps into it on: the
    median samples and stored floats of its steps so far (past their first fifth) at the reference rates
    (:func:`~mi_voldis.fit.schedule.counted_step_seconds`), where the plan modelled the stage from the
    coarse one (its R^COST_EXPONENT growth misses what the stage's strides save and how many vertices its
    carve keeps). The steps ahead then fill what the full phase's budget leaves after the steps before the
    stage (costed as planned) and those of it so far (as counted), at least ``min_steps`` in all
    (:func:`~mi_voldis.fit.schedule.last_stage_steps`): while the counts hold, the end stays where it is.
    Counted, not timed: the same on every machine, and a resumed fit counts what the uninterrupted one did
    (the log is in its checkpoint)."""
    plan = state.plan
    start = state.schedule[-1][0]
    if plan.get("sample_ns") is None or len(state.schedule) < 2 or step - start < REPLAN_EVERY:
        return
    rows = [r for r in state.log if start < r["step"] <= step and "floats" in r and "test_psnr" not in r]
    rows = rows[len(rows) // 5:]
    if len(rows) < 10:
        return
    seconds = counted_step_seconds(plan, float(np.median([r["samples"] for r in rows])),
                                   float(np.median([r["floats"] for r in rows])))
    cost = plan_cost(plan, state.schedule[0][1])
    spent = cost_ahead(state.schedule, state.steps_full, 0, cost) - cost_ahead(state.schedule, state.steps_full, start,
                                                                                cost) + (step - start) * seconds
    steps = last_stage_steps(step, seconds, plan["budget_seconds"] - spent, plan.get("min_steps", 0))
    plan["recounted"] = {"step": step, "step_seconds": seconds}
    if steps != state.steps_full:
        state.steps_full = steps
        plan.setdefault("rescaled", []).append([step, steps])


def plan_schedule(inputs, state, integrator):
    """Freeze the full phase's schedule after the calibration steps (:mod:`mi_voldis.fit.schedule`)."""
    cfg = inputs.cfg
    coarse = coarse_resolution(cfg)
    survey = capture_survey(inputs, integrator, state) if cfg.resolution == "auto" else None
    final = cfg.resolution if survey is None else survey["capture_resolution"]
    if final is None:  # no training ray ends anywhere yet: a voxel per pixel of a view the box would fill
        final = int(min(cfg.max_resolution, 16 * np.ceil(max(inputs.ds.size) / 16)))
    state.plan = {"capture_resolution": int(final)}
    if survey is not None and survey["surface_cells"]:
        state.plan.update(surface_cells=float(survey["surface_cells"]), surface_resolution=survey["surface_resolution"],
                          ray_hits=survey["ray_hits"])
    if cfg.steps_full is None:
        first = cfg.calibration_steps // 5  # past the first steps (kernels compiling)
        rows = [r for r in state.log if r["step"] > first and "test_psnr" not in r]
        minutes = auto_minutes(inputs.ds, backend()) if cfg.minutes == "auto" else cfg.minutes
        host = cfg.host_ms / 1e3
        if cfg.minutes == "auto":  # costed at the reference speed: the same plan on every machine, loaded or not
            kernels = float(np.median([r["samples"] for r in rows])) / (cfg.reference_msps * 1e6)
            cost = StepCost(kernels, coarse, host)
            spent = cfg.calibration_steps * float(cost.at(coarse))
            state.plan.update(min_steps=cfg.min_steps, reference_msps=cfg.reference_msps, sample_ns=cfg.sample_ns,
                              float_ns=cfg.float_ns)
        else:  # this machine's wall clock, re-timed as the fit runs (:func:`replan`)
            cost = StepCost.timed(float(np.median([r["step_seconds"] for r in rows])), coarse, host)
            spent = state.log[-1]["time"] if state.log else 0.0
        full_share = 1.0 - reserved(refits_background(inputs))
        budget = minutes * 60.0 * full_share - spent
        # the minutes a large capture gets past the backend's bound buy steps on the grid the bound's budget
        # picks, not a finer one: such a capture lacks observations (garden's 42 M pixels are each seen 0.6
        # times in 3,000 steps), and more steps on its grid is what gained there (reports/notes.md)
        grid_minutes = auto_minutes(inputs.ds, backend(), grow=False) if cfg.minutes == "auto" else minutes
        grid_budget = grid_minutes * 60.0 * full_share - spent
        state.plan.update(minutes=float(minutes), coarse_step_seconds=float(cost.at(coarse)), host_ms=cfg.host_ms,
                          budget_seconds=minutes * 60.0 * full_share)
        if grid_minutes != minutes:
            state.plan["grid_minutes"] = float(grid_minutes)
        if view_lattice_vertices(cfg, cfg.sh_degree):  # the calibration's steps did not read the view lattice
            state.plan["kernel_scale"] = degree_cost_scale(cfg, cfg.sh_degree)
            cost = plan_cost(state.plan, coarse)
        if survey is not None and survey["surface_cells"]:
            if cfg.step_voxels == "auto":
                state.plan["step_voxels"] = choose_step(cfg, cost, grid_budget, survey, inputs.bank.pixels)
                cost = cost.marching(state.plan["step_voxels"])
            bounds = resolution_bounds(cfg, cost, grid_budget, survey, inputs.bank.pixels)
            state.plan.update(resolution_bounds=bounds, affordable_resolution=min(bounds.values()))
            final = min(final, state.plan["affordable_resolution"])
    state.plan["final_resolution"] = int(final)
    plan_stages = stages(cfg, coarse, final)
    if cfg.steps_full is not None:
        steps = cfg.steps_full
    else:
        steps = max(2 * cfg.calibration_steps, steps_for(plan_stages, cost, budget),
                    stage_floor(state.plan, counted=len(plan_stages) > 1))
    state.steps_full = steps
    state.schedule = schedule_of(plan_stages, steps, cfg.calibration_steps)


def stage_floor(plan, counted):
    """The fewest steps a default plan places its stages over: ``min_steps``, and for a capture whose
    budget grew past the backend's bound (:func:`auto_minutes`) that times ``minutes`` over
    ``grid_minutes`` where its last stage will be ``counted`` (:func:`recount`: more than one stage, the
    count on): the extra minutes buy steps at every stage, not only at the last, and the count then sets
    the end within the budget (at least ``min_steps``). garden's stages placed over 3,000 steps, its last
    one stretched by the count to 4,152: 22.60 dB held out; placed over 4,152 and counted to 4,321: 22.76,
    higher on 17 of 24 views (reports/notes.md)."""
    floor = plan.get("min_steps", 0)
    if counted and "grid_minutes" in plan and plan.get("sample_ns") is not None:
        floor = int(round(floor * plan["minutes"] / plan["grid_minutes"]))
    return floor


BOUND_NAMES = {"observations": "the budget affords", "pixels": "the training pixels afford",
               "memory": "the memory (max_memory_gib) affords"}


def describe_plan(state):
    """One line of the frozen plan: stages (resolution: voxels along the longest side), steps and what
    bounded the final resolution."""
    plan = state.plan
    line = "resolution " + " -> ".join(f"{r} (step {k})" for k, r in state.schedule) + f", {state.steps_full} steps"
    if "minutes" in plan:
        clock = "at the reference speed" if "reference_msps" in plan else "of this machine's wall clock"
        line += f" ({plan['minutes']:.1f} min {clock})"
    if "step_voxels" in plan:
        line += f", samples every {plan['step_voxels']:g} voxel after the coarse stage"
    line += f"; the capture asks {plan['capture_resolution']}"
    if plan.get("affordable_resolution", plan["capture_resolution"]) < plan["capture_resolution"]:
        bounds = plan.get("resolution_bounds", {"observations": plan["affordable_resolution"]})
        bound = min(bounds, key=lambda k: (bounds[k], k == "observations"))  # a tie: the rule a cheaper step keeps
        line += f", {BOUND_NAMES[bound]} {plan['affordable_resolution']}"
    return line


def held_out_psnr(inputs, problem):
    """Held-out PSNR of the full field on a few test views, for the PSNR-vs-time log (None without
    test views), its rays stopped where the fitted scene's are (``scene_stop_transmittance``: what the
    run will render, in fewer samples than fitting's stop)."""
    views = list(inputs.ds.test[: inputs.cfg.eval_views])
    if not views:
        return None
    bank = RayBank(inputs.ds, views)

    def evaluate(step):
        problem.sync_states()
        ds = inputs.ds
        with problem.integrator.stopped_at(inputs.cfg.scene_stop_transmittance) as integrator:
            values = [psnr(ds.as_photographed(render_camera(integrator, bank.cams[k], ("full",))["full"]),
                           ds.images[v]) for k, v in enumerate(views)]
        return {"test_psnr": float(np.mean(values))}
    return evaluate
