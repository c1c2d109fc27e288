"""The pieces of a fit: :class:`FitContext` (dataset, config, field states, optimiser, checkpoints)
and :class:`FieldFit`, one phase as a problem for :func:`mi_voldis.optim.loop.optimize`."""
import os

import drjit as dr
import mitsuba as mi
import numpy as np

from ..data.scene_box import scene_space
from ..device import from_numpy
from ..optim.adam import Adam
from ..optim.loop import Checkpoint
from ..render.rays import render_rays
from ..render.views import render_camera
from . import grids
from .raybank import RayBank


class PackedParameters(dict):
    """The fields' packed grids as the optimised parameters, ``{"role.packed": Float}``.

    Adam steps on the very arrays the march reads: a step neither packs density and colour tensors
    nor unpacks their gradients (at 128^3 that is three passes over 32 MB per field and step).
    ``update()`` hands changed arrays back to the fields; ``per_slot`` lays out per-channel values
    (Adam's learning rates, regulariser weights) in the packed layout."""

    def __init__(self, fields):
        self.fields = dict(fields)
        super().__init__({f"{r}.packed": f.packed for r, f in self.fields.items()})

    def update(self):
        for key, value in self.items():
            field = self.fields[key.split(".")[0]]
            if value is not field.packed:
                field.set_packed(value)

    def per_slot(self, role, density, color):
        """Values for the slots of one packed vertex: ``density`` for channel 0, ``color`` for the
        colour channels, 0 for the padding."""
        f = self.fields[role]
        return [density] + [color] * (f.channels - 1) + [0.0] * (f.width - f.channels)


class FieldFit:
    """One fitting phase as a problem for :func:`optimize`: which fields, which layers, which rays."""

    def __init__(self, ctx, roles, layers, bank, pool=None, hull=None, phase=0, schedule=True, adam=None,
                 rates=None):
        self.ctx, self.roles, self.layers, self.bank = ctx, roles, layers, bank
        self.pool, self.hull, self.phase, self.schedule = pool, hull, phase, schedule
        self.adam = ctx.adam if adam is None else adam
        self.rates = (ctx.cfg.lr_density, ctx.cfg.lr_color) if rates is None else rates  # (density, colour)
        self.rebuild()

    # -- plumbing
    def rebuild(self):
        ctx = self.ctx
        self.integrator = ctx.build_integrator()
        self.params = PackedParameters({r: self.integrator.fields[r] for r in self.roles})
        self.keys = list(self.params)
        for r in self.roles:
            self.adam.lrs[f"{r}.packed"] = self.params.per_slot(r, *self.rates)
        self.samples = None  # the integrator's: at most max_samples, every step_size
        if ctx.occupancy_on:
            extra = ctx.hull_points if self.hull is not None else None
            self.integrator.update_occupancy(ctx.cfg.occupancy_resolution, ctx.occupancy_sigma(), extra)

    def sync_states(self):
        for r in self.roles:
            s, f = self.ctx.states[r], self.integrator.fields[r]
            s.density, s.color = f.density, f.color

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
            self.adam.reset()
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
        o, d, color, mask = self.bank.batch(rng, n, self.pool, ctx.cfg.batch_tile)
        out = render_rays(self.integrator, o, d, from_numpy(mi.Float, rng.random(n, np.float32)), self.layers,
                          self.samples)
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
        """Regularisers on the packed grids (channel 0 density, then colour; padding untouched):
        sparsity on activated density, total variation every ``tv_every`` steps, and the hull mask."""
        cfg = self.ctx.cfg
        tv = cfg.tv_every if step % cfg.tv_every == 0 else 0.0
        for r in self.roles:
            key, f = f"{r}.packed", self.integrator.fields[r]
            values = dr.detach(self.params[key])
            vertices = dr.width(values) // f.width
            channel = dr.arange(mi.UInt32, dr.width(values)) % f.width
            g = grads[key] + dr.select(channel == 0, (cfg.sparsity / vertices) * dr.rcp(1.0 + dr.exp(-values)), 0.0)
            if tv:  # grids.laplacian averages over every slot: rescale to per-vertex means of each tensor
                weights = self.params.per_slot(r, tv * cfg.tv_density * f.width,
                                               tv * cfg.tv_color * f.width / (f.channels - 1))
                weight = dr.gather(mi.Float, from_numpy(mi.Float, weights), channel)
                g = g + weight * grids.laplacian(mi.TensorXf(values, (*f.shape[::-1], f.width)))
            if self.hull is not None:  # refit only inside the hull
                g = g * dr.repeat(self.hull, f.width)
            grads[key] = g
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
        return from_numpy(mi.Color3f, rng.random((3, n), np.float32).T)

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
