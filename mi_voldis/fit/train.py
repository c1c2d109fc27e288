"""Fit the full-scene and background radiance fields of a dataset (paper Sec. 3.1).

    L_full = sum_i ||x_i - x^_i||^2 over all pixels,   L_bg = sum_i ||(1 - m_i)(x_i - x^_i)||^2,

both through the ``voldis`` integrator's renders (same sampler, quadrature and mixing as every later
task) and Dr.Jit's reverse-mode AD, with Adam on raw voxel grids.

Phases (``bg_strategy``):

* ``refit`` (default): fit the full field; then the background starts as a copy of it, the
  object's visual hull (from the masks) is cleared, and only hull cells are refitted with L_bg on
  rays near the masks. Outside the hull the two fields are identical, so the foreground
  w_full - w_bg is exactly zero there.
* ``scratch``: both fields from scratch, jointly, on the same rays (two layers of one march).

Where the background has no density its colour is unconstrained, yet c_fg = c_full - c_bg reads it;
after fitting, background colour is set to black wherever its voxel opacity is negligible, so that
there c_fg = c_full (``empty_color_alpha``).
"""
import time

import drjit as dr
import numpy as np

from ..metrics import psnr
from ..optim.loop import optimize
from . import grids
from .background import background_ray_pool, background_regions, clear_empty_background_color, start_background
from .problem import FieldFit, FitContext
from .raybank import RayBank
from .sh_degree import choose_sh_degree


def fit(dataset, run_dir, cfg, resume=False, progress=True):
    """Fit ``dataset`` into ``run_dir`` (a staging folder; see :mod:`mi_voldis.fit.run`). Returns the
    context holding the fitted states, the log and the phase times."""
    ctx = FitContext(dataset, cfg, run_dir)
    ctx.progress = progress
    meta = ctx.load() if resume else None
    if resume and meta is None:
        raise ValueError(f"{run_dir}: no checkpoint to resume from")
    start_phase, start_step = (meta["phase"], meta["step"]) if meta else ("full", 0)
    has_masks = dataset.masks is not None
    scratch = cfg.bg_strategy == "scratch" and has_masks
    if cfg.bg_strategy not in ("refit", "scratch"):
        raise ValueError(f"bg_strategy must be 'refit' or 'scratch', got '{cfg.bg_strategy}'")
    roles = ("full", "bg") if scratch else ("full",)
    if meta is None:
        ctx.init_fields(roles, 0 if cfg.sh_degree in ("auto", 0, "0") else int(cfg.sh_degree))

    def checkpoint(phase):
        return lambda step: ctx.save(phase, step)

    if start_phase == "full":
        problem = FieldFit(ctx, roles, roles, ctx.bank)
        t0 = time.perf_counter()
        sh_step = cfg.tighten_at_step or cfg.resolution_schedule[-1][0]
        eval_fn = make_eval(ctx, problem)
        if cfg.sh_degree == "auto" and start_step < sh_step:
            optimize(problem, ctx.adam, sh_step, start_step, cfg.lr_final_ratio ** (sh_step / cfg.steps_full),
                     ctx.log, "full (coarse)", checkpoint("full"), cfg.checkpoint_every, eval_fn, cfg.eval_every,
                     progress)
            problem.sync_states()
            choose_sh_degree(ctx, roles, cfg)
            ctx.adam.reset()
            problem.rebuild()
            start_step = sh_step
        optimize(problem, ctx.adam, cfg.steps_full, start_step, cfg.lr_final_ratio, ctx.log,
                 "full" if not scratch else "full + bg", checkpoint("full"), cfg.checkpoint_every, eval_fn,
                 cfg.eval_every, progress)
        problem.sync_states()
        ctx.phase_times["full"] = ctx.phase_times.get("full", 0.0) + time.perf_counter() - t0
        start_phase, start_step = "bg", 0
        ctx.adam.reset()
        ctx.save("bg", 0)

    if start_phase == "bg" and has_masks and not scratch:
        t0 = time.perf_counter()
        if "bg" not in ctx.states or ctx.hull_points is None:
            start_background(ctx)
        hull, _, obj = background_regions(ctx)
        free = dr.select(obj, 0.0, hull)  # refit the hull but the object's own voxels, which stay empty
        pool = background_ray_pool(dataset, ctx.bank, cfg.bg_ray_dilation)
        problem = FieldFit(ctx, ("bg",), ("bg",), ctx.bank, pool=pool, hull=free, phase=1, schedule=False)
        optimize(problem, ctx.adam, cfg.steps_bg, start_step, cfg.lr_final_ratio, ctx.log, "bg refit",
                 checkpoint("bg"), cfg.checkpoint_every, None, 0, progress)
        problem.sync_states()
        ctx.phase_times["bg"] = ctx.phase_times.get("bg", 0.0) + time.perf_counter() - t0
    if "bg" not in ctx.states:  # no masks: nothing to disentangle, the background is the full scene
        full = ctx.states["full"]
        ctx.states["bg"] = grids.FieldState(full.density, full.color, full.to_world.copy(), full.density_scale)
    if has_masks:
        ctx.empty_color_fraction = clear_empty_background_color(ctx)
    ctx.save("done", 0)
    return ctx


def make_eval(ctx, problem):
    """Held-out PSNR of the full field on a few test views, for the PSNR-vs-time log."""
    views = list(ctx.ds.test[: ctx.cfg.eval_views])
    if not views:
        return None
    bank = RayBank(ctx.ds, views)

    def evaluate(step):
        problem.sync_states()
        integ = problem.integrator
        values = [psnr(ctx.render_view(integ, bank, k, ("full",), problem.samples)["full"][0], ctx.ds.images[v])
                  for k, v in enumerate(views)]
        return {"test_psnr": float(np.mean(values))}
    return evaluate
