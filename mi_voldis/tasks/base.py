"""What every manipulation task shares: the fitted run it reads, edit fields, the optimisation
problem for :func:`mi_voldis.optim.loop.optimize`, and the files a task writes.

A task is only (a) which fields are free and (b) its loss; :class:`EditProblem` turns those into the
problem the optimisation driver runs, and :class:`TaskOutput` writes RUN/<task>/ (staged and swapped
into place like a fit, with checkpoints for ``--resume``).
"""
import json
import os
import shutil

import drjit as dr
import mitsuba as mi
import numpy as np

from ..data import DatasetError, load_dataset
from ..device import from_numpy
from ..export import linear_channels, previews
from ..fit import grids
from ..fit.raybank import RayBank
from ..fit.report import peak_rss_mib, plot_log, write_json
from ..io.exr import write_exr
from ..io.images import contact_sheet, write_png
from ..io.scene_xml import save_field, sensor_xml, write_scene
from ..metrics import dilate
from ..optim.loop import Checkpoint, optimize
from ..render.rays import render_rays
from ..render.views import layer_channels, render_camera

PREVIEW_VIEWS = 3


class FittedRun:
    """A fitting run directory: its dataset, fields and integrator settings."""

    def __init__(self, run_dir, dataset=None):
        self.dir = run_dir
        scene = os.path.join(run_dir, "scene.xml")
        if not os.path.isfile(scene):
            raise ValueError(f"{run_dir}: not a fitted run (no scene.xml); run scripts/train.py first")
        with open(os.path.join(run_dir, "config.json")) as f:
            self.config = json.load(f)
        dataset = dataset or self.config.get("dataset")
        try:
            self.dataset = load_dataset(dataset)
        except DatasetError as e:
            raise ValueError(f"{run_dir}: its dataset cannot be loaded ({e}); pass --dataset") from None
        self.scene = mi.load_file(scene)
        base = self.scene.integrator()
        self.fields = dict(base.fields)
        self.space = base.space
        self.options = {"samples": base.samples, "step_size": base.step_size, "composition": base.composition}
        self.occupancy = (int(self.config.get("occupancy_resolution", 0)), base.occupancy_threshold)

    def integrator(self, fields=None, **props):
        """A ``voldis`` integrator over this run's fields (plus ``fields``) with extra properties."""
        spec = {"type": "voldis", **self.options, **self.fields, **(fields or {}), **props}
        for key, value in self.space.properties().items():
            spec[key] = mi.ScalarTransform4f(np.asarray(value, np.float32)) if key == "ndc_to_world" else float(value)
        integ = mi.load_dict(spec, optimize=False)
        if self.occupancy[0]:
            integ.update_occupancy(*self.occupancy)
        return integ

    def foreground_box(self, margin=0.1, threshold_alpha=1e-2):
        """Scene-space box around where the full and background fields differ (the object's
        disentangled volume), grown by ``margin`` of its size; the whole field box if they never do."""
        full, bg = self.fields["full"], self.fields["bg"]
        a, b = np.array(full.density)[..., 0], np.array(bg.density)[..., 0]
        if a.shape != b.shape:
            raise ValueError("full and background grids differ in shape; cannot locate the object")
        voxel = np.max(np.diag(full.to_world)[:3] / (np.array(full.shape) - 1))
        raw = grids.density_raw_for_alpha(threshold_alpha, voxel, full.density_scale)
        diff = (np.maximum(a, b) > raw) & (np.abs(a - b) > 1e-3)
        z, y, x = np.nonzero(diff)
        corners = np.array([[0, 0, 0], [1, 1, 1]], np.float64)
        if len(x):
            res = np.array(full.shape, np.float64) - 1
            corners = np.stack([[x.min(), y.min(), z.min()], [x.max(), y.max(), z.max()]]) / res
        pts = corners @ full.to_world[:3, :3].T + full.to_world[:3, 3]
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        pad = margin * (hi - lo) + 2 * voxel
        return lo - pad, hi + pad

    def foreground_centre_world(self):
        lo, hi = self.foreground_box(margin=0.0)
        return self.space.to_world_np(0.5 * (lo + hi)[None])[0]


def edit_field(lo, hi, resolution, density_raw=-30.0, color_raw=0.0, channels=3, density_scale=1.0):
    """Plugin dict of a new field over the scene-space box [lo, hi] (``resolution`` vertices along
    its longest side), constant raw density and colour."""
    shape = grids.shape_for(lo, hi, resolution)
    state = grids.init_state(lo, hi, resolution, (int(np.sqrt(channels // 3)) - 1), density_raw, density_scale)
    z, y, x = shape[::-1]
    state.color = dr.full(mi.TensorXf, color_raw, (z, y, x, channels))
    return state.plugin()


class EditProblem:
    """Optimisation problem over named field tensors with a loss on random training rays.

    ``loss_fn(out, color, mask)`` builds the loss from the rendered layers of a batch of rays of the
    training views (``pool``: optional subset of pixel indices, e.g. near the object)."""

    def __init__(self, run, integrator, keys, layers, loss_fn, batch=4096, pool=None, seed=0):
        self.run, self.integrator, self.keys, self.layers = run, integrator, keys, layers
        self.loss_fn, self.batch, self.pool, self.seed = loss_fn, batch, pool, seed
        self.params = mi.traverse(integrator)
        self.bank = RayBank(run.dataset, run.dataset.train)

    def loss(self, step):
        rng = np.random.default_rng([self.seed, 7, step])
        n = self.batch
        o, d, color, mask = self.bank.batch(rng, n, self.pool)
        out = render_rays(self.integrator, o, d, from_numpy(mi.Float, rng.random(n, np.float32)), self.layers)
        loss = self.loss_fn(out, color, mask)
        return loss, {"samples": float(dr.sum(out["evaluated"])[0])}


def pixels_near_object(run, dilation=0.1):
    """Flat pixel indices (training views, row-major) within the object masks dilated by ``dilation``
    of the image diagonal; all pixels when the dataset has no masks."""
    ds = run.dataset
    if ds.masks is None:
        return None
    near = dilate(ds.masks[ds.train], int(np.ceil(dilation * np.hypot(*ds.size))))
    return np.flatnonzero(near.reshape(-1)).astype(np.uint32)


class TaskOutput:
    """RUN/<task>/, written into RUN/<task>.partial and renamed when complete."""

    def __init__(self, run, task, resume=False):
        self.run, self.task = run, task
        self.final = os.path.join(run.dir, task)
        self.dir = self.final + ".partial"
        if resume and not os.path.isdir(self.dir):
            raise ValueError(f"{self.dir}: nothing to resume")
        if not resume:
            shutil.rmtree(self.dir, ignore_errors=True)
        os.makedirs(self.dir, exist_ok=True)
        self.checkpoint = Checkpoint(os.path.join(self.dir, "checkpoints", "last.npz"))

    def write_scene(self, fields, options, transforms=None):
        """Fields as .vol files and scene.xml (with a sensor per held-out view)."""
        bodies = {role: save_field(self.dir, role, np.array(f.density), np.array(f.color), f.to_world,
                                   f.density_scale) for role, f in fields.items()}
        opts = {**self.run.options, "occupancy_resolution": self.run.occupancy[0],
                "occupancy_threshold": float(self.run.occupancy[1]), **options}
        transforms = dict(transforms or {})
        for key, value in self.run.space.properties().items():
            if key == "ndc_to_world":
                transforms[key] = value
            else:
                opts[key] = float(value)
        ds = self.run.dataset
        sensors = [sensor_xml(c.to_world, c.fov_x, c.width, c.height, 1, c.principal)
                   for c in (ds.cameras[v] for v in ds.test)]
        path = os.path.join(self.dir, "scene.xml")
        write_scene(path, bodies, opts, sensors, transforms)
        return path

    def write_views(self, integrator, views=None, main="composite", extra=()):
        """Layered EXR and PNG previews of held-out views; returns {view: layers}."""
        ds = self.run.dataset
        views = list(ds.test if views is None else views)
        renders = {}
        layers = tuple(dict.fromkeys(("composite", "full", "bg", "fg", main) + tuple(extra)))
        for v in views:
            out = render_camera(integrator, ds.cameras[v], layers)
            renders[v] = out
            channels = layer_channels(out, main)
            write_exr(os.path.join(self.dir, f"view{v:03d}.exr"), linear_channels(channels))
            if len(renders) <= PREVIEW_VIEWS:
                images = previews(channels, [lay for lay in ("full", "bg", "fg", "res") if lay in out])
                for name, image in images.items():
                    write_png(os.path.join(self.dir, f"view{v:03d}_{name}.png"), image)
                write_png(os.path.join(self.dir, f"view{v:03d}_sheet.png"), contact_sheet(list(images.values())))
        return renders

    def finish(self, metrics, log=None):
        if log:
            plot_log(os.path.join(self.dir, "loss.png"), log, f"{self.task}: loss against time")
            write_json(os.path.join(self.dir, "log.json"), log)
        write_json(os.path.join(self.dir, "metrics.json"), {**metrics, "peak_rss_mib": peak_rss_mib()})
        old = self.final + ".old"
        shutil.rmtree(old, ignore_errors=True)
        if os.path.exists(self.final):
            os.replace(self.final, old)
        os.replace(self.dir, self.final)
        shutil.rmtree(old, ignore_errors=True)
        return self.final


def run_optimisation(output, problem, adam, steps, desc, options, final_ratio=0.1):
    """Optimise ``problem`` with checkpoints in ``output`` every ``options["checkpoint_every"]`` steps
    (default 100), resumable after a crash or kill -9 (``options["resume"]``)."""
    every = int(options.get("checkpoint_every") or 100)
    start, log = 0, []
    if options.get("resume"):
        loaded = output.checkpoint.load()
        if loaded is not None:
            arrays, meta = loaded
            for key in problem.keys:
                problem.params[key] = mi.TensorXf(arrays[f"param/{key}"])
            problem.params.update()
            adam.load({k[5:]: v for k, v in arrays.items() if k.startswith("adam/")}, meta["adam_t"])
            start, log = meta["step"], meta["log"]

    def save(step):
        arrays = {f"param/{k}": np.array(problem.params[k]) for k in problem.keys}
        adam_arrays, t = adam.state()
        arrays.update({f"adam/{k}": v for k, v in adam_arrays.items()})
        output.checkpoint.save(arrays, {"step": step, "log": log, "adam_t": t})

    optimize(problem, adam, steps, start, final_ratio, log, desc, save, every, progress=options.get("progress", True))
    return log
