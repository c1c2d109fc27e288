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
import os
import time

import drjit as dr
import mitsuba as mi
import numpy as np

from ..data.scene_box import scene_space
from ..grid import dilate_cells
from ..metrics import dilate, psnr
from ..optim.adam import Adam
from ..optim.loop import Checkpoint, optimize
from ..render.rays import render_rays
from ..render.views import render_camera
from . import grids
from .hull import visual_hull
from .raybank import RayBank


class FieldFit:
    """One fitting phase as a problem for :func:`optimize`: which fields, which layers, which rays."""

    def __init__(self, ctx, roles, layers, bank, pool=None, hull=None, phase=0, schedule=True):
        self.ctx, self.roles, self.layers, self.bank = ctx, roles, layers, bank
        self.pool, self.hull, self.phase, self.schedule = pool, hull, phase, schedule
        self.rebuild()

    # -- plumbing
    def rebuild(self):
        ctx = self.ctx
        self.integrator = ctx.build_integrator()
        self.params = mi.traverse(self.integrator)
        self.keys = [f"{r}.{k}" for r in self.roles for k in ("density", "color")]
        self.samples = None  # the integrator's: at most max_samples, every step_size
        if ctx.occupancy_on:
            extra = ctx.hull_points if self.hull is not None else None
            self.integrator.update_occupancy(ctx.cfg.occupancy_resolution, ctx.occupancy_sigma(), extra)

    def sync_states(self):
        for r in self.roles:
            s = self.ctx.states[r]
            s.density, s.color = self.params[f"{r}.density"], self.params[f"{r}.color"]

    # -- schedule
    def before_step(self, step):
        ctx, cfg = self.ctx, self.ctx.cfg
        tighten = self.schedule and cfg.tighten_at_step and step == cfg.tighten_at_step and not ctx.occupancy_on
        upsample = self.schedule and any(step == start for start, _ in cfg.resolution_schedule[1:])
        if tighten or upsample:
            self.sync_states()  # once: the states are replaced below
            if tighten:
                ctx.tighten(self.integrator)
            if upsample:
                ctx.resample(self.roles, ctx.target_resolution(step))
            ctx.adam.reset()
            self.rebuild()
        elif ctx.occupancy_on and step % cfg.occupancy_every == 0 and step > 0:
            self.sync_states()
            extra = ctx.hull_points if self.hull is not None else None
            self.integrator.update_occupancy(cfg.occupancy_resolution, ctx.occupancy_sigma(), extra)

    # -- loss
    def loss(self, step):
        ctx = self.ctx
        rng = np.random.default_rng([ctx.cfg.seed, self.phase, step])
        n = ctx.cfg.batch_rays
        o, d, color, mask = self.bank.batch(rng, n, self.pool)
        out = render_rays(self.integrator, o, d, mi.Float(rng.random(n, np.float32)), self.layers, self.samples)
        behind = ctx.behind(rng, n)  # what shows through where a layer is not opaque
        loss = mi.Float(0.0)
        stats = {"samples": float(dr.sum(out["evaluated"])[0])}
        if "full" in self.layers:
            err = dr.mean(dr.squared_norm(out["full"][0] + (1.0 - out["full"][1]) * behind - color)) / 3.0
            loss += err
            stats["psnr"] = -10 * np.log10(max(float(err[0]), 1e-12))
        if "bg" in self.layers:
            keep = 1.0 - mask
            pred = out["bg"][0] + (1.0 - out["bg"][1]) * behind
            err = dr.sum(keep * dr.squared_norm(pred - color)) / (3.0 * dr.maximum(dr.sum(keep), 1.0))
            loss += err
            stats["psnr_bg"] = -10 * np.log10(max(float(err[0]), 1e-12))
        return loss, stats

    def extra_gradients(self, step, grads):
        cfg = self.ctx.cfg
        tv = cfg.tv_every if step % cfg.tv_every == 0 else 0.0
        for r in self.roles:
            d, c = dr.detach(self.params[f"{r}.density"]), dr.detach(self.params[f"{r}.color"])
            g_d = grads[f"{r}.density"] + (cfg.sparsity / dr.width(d.array)) * dr.rcp(1.0 + dr.exp(-d.array))
            g_c = grads[f"{r}.color"]
            if tv:
                g_d = g_d + (tv * cfg.tv_density) * grids.laplacian(d)
                g_c = g_c + (tv * cfg.tv_color) * grids.laplacian(c)
            if self.hull is not None:  # refit only inside the hull
                g_d = g_d * self.hull
                g_c = g_c * dr.repeat(self.hull, c.shape[3])
            grads[f"{r}.density"], grads[f"{r}.color"] = g_d, g_c
        return grads


class FitContext:
    """Shared state of a fit: dataset, config, field states, optimiser, the run directory."""

    def __init__(self, dataset, cfg, run_dir):
        self.ds, self.cfg, self.run_dir = dataset, cfg, run_dir
        self.space = scene_space(dataset.box)
        self.lo, self.hi = np.asarray(dataset.box.lo, np.float64), np.asarray(dataset.box.hi, np.float64)
        self.bank = RayBank(dataset, dataset.train)
        self.states = {}
        self.occupancy_on = False
        self.hull_points = None
        self.adam = Adam({}, cfg.adam_beta1, cfg.adam_beta2, warmup=cfg.lr_warmup)
        self.log = []
        self.phase_times = {}
        self.sh_choice = None
        self.progress = True

    # -- grids
    def target_resolution(self, step):
        res = self.cfg.resolution_schedule[0][1]
        for start, r in self.cfg.resolution_schedule:
            if step >= start:
                res = r
        return res

    def init_fields(self, roles, sh_degree):
        res = self.cfg.resolution_schedule[0][1]
        step = self.cell(res) * self.cfg.step_voxels
        scale = 1.0 / self.cell(self.cfg.resolution_schedule[-1][1])  # raw densities per finest voxel
        raw = grids.density_raw_for_alpha(self.cfg.density_init_alpha, step, scale)
        for r in roles:
            self.states[r] = grids.init_state(self.lo, self.hi, res, sh_degree, raw, scale)

    def cell(self, res):
        return float((self.hi - self.lo).max() / (res - 1))

    def resample(self, roles, res):
        for r in roles:
            self.states[r] = grids.resample(self.states[r], res)

    def tighten(self, integrator):
        """Shrink the box to the space the training rays end in; skip empty space from now on."""
        box = self.seen_box(integrator)
        if box is not None:
            self.lo, self.hi = box
            empty = grids.density_raw_for_alpha(1e-6, 1.0, self.states["full"].density_scale)
            for r in list(self.states):
                self.states[r] = grids.resample(self.states[r], max(self.states[r].shape), self.lo, self.hi, empty)
        self.occupancy_on = self.cfg.occupancy_resolution > 0

    def seen_box(self, integrator, rays=1 << 16):
        """Scene-space bounds of where random training rays end (alpha > 0.5, at their expected
        depth), grown by ``tighten_margin`` of the size and two voxels; None if no ray ends."""
        rng = np.random.default_rng([self.cfg.seed, 99])
        idx = rng.integers(0, self.bank.pixels, rays).astype(np.uint32)
        o, d, _, _ = self.bank.rays(idx, np.full((rays, 2), 0.5, np.float32))
        with dr.suspend_grad():
            out = render_rays(integrator, o, d, dr.full(mi.Float, 0.5, rays), ("full",))
        alpha, depth = np.array(out["full"][1]), np.array(out["full"][2])
        keep = alpha > 0.5
        if not keep.any():
            return None
        pts = np.array(o).T[keep] + depth[keep, None] * np.array(d).T[keep]
        pts = self.space.from_world_np(pts)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        pad = self.cfg.tighten_margin * (hi - lo) + 2 * grids.voxel_size(self.states["full"])
        return np.maximum(lo - pad, self.lo), np.minimum(hi + pad, self.hi)

    def behind(self, rng, n):
        """Colour seen through a layer's remaining transmittance in training: the dataset's background
        colour for composited RGBA images, else a random colour per ray, so that no fit can explain a
        pixel with a half-transparent surface over black (every ray of a closed capture ends on one)."""
        bg = self.ds.meta.get("background_color")
        if bg is not None:
            return mi.Color3f(*bg)
        return mi.Color3f(*rng.random((3, n), np.float32))

    def occupancy_sigma(self):
        """Density (per scene unit) of a voxel of opacity ``occupancy_alpha`` at the current grid."""
        return -np.log1p(-self.cfg.occupancy_alpha) / grids.voxel_size(self.states["full"])

    def step_size(self):
        """Sample spacing along rays (scene units): ``step_voxels`` of the current grid's voxels."""
        return self.cfg.step_voxels * grids.voxel_size(self.states["full"])

    def build_integrator(self):
        full = self.states["full"]
        bg = self.states.get("bg")
        if bg is None:  # the full phase of "refit": an empty stand-in background over the same box
            bg = grids.FieldState(dr.full(mi.TensorXf, -30.0, (2, 2, 2, 1)), dr.zeros(mi.TensorXf, (2, 2, 2, 3)),
                                  full.to_world)
        props = {"type": "voldis", "full": full.plugin(), "bg": bg.plugin(), "samples": self.cfg.max_samples,
                 "step_size": self.step_size()}
        props.update(_space_props(self.space))
        return mi.load_dict(props, optimize=False)

    # -- checkpoints
    def save(self, phase, step):
        arrays = {}
        meta = {"phase": phase, "step": step, "lo": self.lo.tolist(), "hi": self.hi.tolist(),
                "occupancy_on": self.occupancy_on, "log": self.log, "phase_times": self.phase_times,
                "sh_choice": self.sh_choice}
        for r, s in self.states.items():
            arrays[f"{r}/density"] = np.array(s.density)
            arrays[f"{r}/color"] = np.array(s.color)
            arrays[f"{r}/to_world"] = s.to_world
            arrays[f"{r}/density_scale"] = np.array(s.density_scale)
        adam_arrays, meta["adam_t"] = self.adam.state()
        arrays.update({f"adam/{k}": v for k, v in adam_arrays.items()})
        if self.hull_points is not None:
            arrays["hull_points"] = self.hull_points
        Checkpoint(os.path.join(self.run_dir, "checkpoints", "last.npz")).save(arrays, meta)

    def load(self):
        loaded = Checkpoint(os.path.join(self.run_dir, "checkpoints", "last.npz")).load()
        if loaded is None:
            return None
        arrays, meta = loaded
        for r in ("full", "bg"):
            if f"{r}/density" in arrays:
                self.states[r] = grids.FieldState(
                    mi.TensorXf(arrays[f"{r}/density"]), mi.TensorXf(arrays[f"{r}/color"]), arrays[f"{r}/to_world"],
                    float(arrays[f"{r}/density_scale"]))
        self.lo, self.hi = np.array(meta["lo"]), np.array(meta["hi"])
        self.occupancy_on = meta["occupancy_on"]
        self.log, self.phase_times, self.sh_choice = meta["log"], meta["phase_times"], meta["sh_choice"]
        self.adam.load({k[5:]: v for k, v in arrays.items() if k.startswith("adam/")}, meta["adam_t"])
        self.hull_points = arrays.get("hull_points")
        return meta

    # -- evaluation
    def render_view(self, integrator, views, k, layers=("composite", "full", "bg", "fg"), samples=None):
        """Layers of dataset view ``views[k]`` (``views``: a :class:`RayBank`)."""
        return render_camera(integrator, views.cams[k], layers, samples)


def _space_props(space):
    props = {}
    for key, value in space.properties().items():
        props[key] = mi.ScalarTransform4f(np.asarray(value, np.float32)) if key == "ndc_to_world" else float(value)
    return props




def choose_sh_degree(ctx, roles, cfg):
    """Degree 1 only if view dependence pays. With the current geometry fixed, colour is fitted from
    scratch at degree 0 and at degree 1 on most training views, and the two are compared on the
    others (every 4th training view, unseen by both colour fits)."""
    train = np.asarray(ctx.ds.train)
    val, fit = train[::4], np.setdiff1d(train, train[::4])
    fit_bank, val_bank = RayBank(ctx.ds, fit), RayBank(ctx.ds, val)
    kept = {r: ctx.states[r] for r in roles}
    scores = {}
    for degree in (0, 1):
        for r in roles:
            colour = grids.with_sh_degree(kept[r], degree).color
            ctx.states[r] = grids.FieldState(kept[r].density, dr.zeros(mi.TensorXf, colour.shape), kept[r].to_world,
                                             kept[r].density_scale)
        trial = FieldFit(ctx, roles, ("full",), fit_bank, phase=10 + degree, schedule=False)
        adam = Adam({f"{r}.color": cfg.lr_color * 2 for r in roles}, cfg.adam_beta1, cfg.adam_beta2)
        optimize(trial, adam, cfg.sh_trial_steps, final_ratio=0.3, desc=f"SH degree {degree} trial",
                 progress=ctx.progress)
        trial.sync_states()
        integ = ctx.build_integrator()
        scores[degree] = float(np.mean([psnr(ctx.render_view(integ, val_bank, k, ("full",))["full"][0],
                                             ctx.ds.images[v]) for k, v in enumerate(val)]))
    degree = int(scores[1] - scores[0] >= cfg.sh_gain_db)
    for r in roles:  # keep the main fit's colour, at the chosen degree
        ctx.states[r] = grids.with_sh_degree(kept[r], degree)
    ctx.sh_choice = {"val_psnr_degree0": scores[0], "val_psnr_degree1": scores[1], "degree": degree,
                     "val_views": val.tolist()}
    return degree


def hull_region(ctx, state):
    """Per-vertex hull indicator (Float, 1 inside) of ``state``'s grid and the hull vertices'
    scene-space positions; the hull is grown by one voxel."""
    cfg = ctx.cfg
    pts_scene = np.array(grids.vertex_positions(state)).T
    pts_world = ctx.space.to_world_np(pts_scene)
    diag = np.hypot(*ctx.ds.size)
    train = ctx.ds.train
    inside = visual_hull(pts_world, [ctx.ds.cameras[v] for v in train], ctx.ds.masks[train],
                         int(np.ceil(cfg.hull_dilation * diag)), cfg.hull_min_views)
    sx, sy, sz = state.shape
    grown = dilate_cells(inside.reshape(sz, sy, sx))
    return mi.Float(grown.ravel().astype(np.float32)), pts_scene[grown.ravel()]


def start_background(ctx):
    """Background = full field with the object's visual hull inpainted from around it: a harmonic
    extension of density and colour, so surfaces the object hides (the floor under it) continue
    through the hull, except in the object's own dense voxels (full-field opacity per voxel above
    ``object_alpha``), which are emptied so that w_fg = w_full - w_bg keeps the whole object; then
    L_bg refits what some view sees."""
    full = ctx.states["full"]
    hull, points, obj = background_regions(ctx)
    voxel = ctx.cell(max(full.shape))
    empty = grids.density_raw_for_alpha(ctx.cfg.density_init_alpha, voxel * ctx.cfg.step_voxels, full.density_scale)
    density = grids.harmonic_fill(full.density, hull)
    density = mi.TensorXf(dr.select(obj, empty, density.array), full.density.shape)
    color = grids.harmonic_fill(full.color, hull)  # black in the object itself: there c_fg = c_full
    color = mi.TensorXf(dr.select(dr.repeat(obj, full.color.shape[3]), grids.EMPTY_COLOR, color.array),
                        full.color.shape)
    ctx.states["bg"] = grids.FieldState(density, color, full.to_world.copy(), full.density_scale)
    ctx.hull_points = points


def background_regions(ctx):
    """The visual hull (Float per vertex), its vertices' positions, and the object's own voxels
    (Bool: hull vertices whose full-field opacity per voxel exceeds ``object_alpha``)."""
    full = ctx.states["full"]
    hull, points = hull_region(ctx, full)
    voxel = ctx.cell(max(full.shape))
    dense = full.density.array > grids.density_raw_for_alpha(ctx.cfg.object_alpha, voxel, full.density_scale)
    return hull, points, (hull > 0) & dense


def background_ray_pool(ds, bank, dilation):
    """Flat indices (into ``bank``) of unmasked pixels within the masks dilated by ``dilation``."""
    diag = np.hypot(*ds.size)
    near = dilate(bank.masks_np, int(np.ceil(dilation * diag))) & ~bank.masks_np
    return np.flatnonzero(near.reshape(-1)).astype(np.uint32)


def clear_empty_background_color(ctx):
    """Set background colour to black at vertices that no visible background sample reads: those
    whose voxel opacity is below ``empty_color_alpha`` and whose neighbours (which share trilinear
    cells with them) are all below it too."""
    bg = ctx.states["bg"]
    step = ctx.cell(max(bg.shape))
    threshold = grids.density_raw_for_alpha(ctx.cfg.empty_color_alpha, step, bg.density_scale)
    occupied = np.array(bg.density)[..., 0] >= threshold
    empty = mi.Bool(~dilate_cells(occupied).ravel())
    c = bg.color.shape[3]
    color = dr.select(dr.repeat(empty, c), grids.EMPTY_COLOR, bg.color.array)
    ctx.states["bg"] = grids.FieldState(bg.density, mi.TensorXf(color, bg.color.shape), bg.to_world, bg.density_scale)
    return float(dr.mean(mi.Float(empty))[0])


PHASES = ("full", "bg")


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

    lrs = {f"{r}.{k}": (cfg.lr_density if k == "density" else cfg.lr_color) for r in ("full", "bg")
           for k in ("density", "color")}
    ctx.adam.lrs = lrs

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
