"""What every manipulation task shares: the fitted run it reads, edit fields, the optimisation
problem for :func:`mi_voldis.optim.loop.optimize`, and the files a task writes.

A task is only (a) which fields are free and (b) its loss (:mod:`mi_voldis.losses`);
:class:`EditProblem` turns those into the problem the optimisation driver runs, and
:class:`TaskOutput` writes RUN/<task>/ (staged and swapped into place like a fit, with checkpoints
for ``resume``).
"""
import json
import os

import drjit as dr
import mitsuba as mi
import numpy as np

from ..data import DatasetError, load_dataset
from ..device import from_numpy
from ..export import write_layers
from ..field.spec import box_transform, field_dict
from ..field.state import density_raw_for_alpha, shape_for
from ..io.run_folder import Checkpoint, peak_rss_mib, write_json
from ..metrics import diagonal_pixels, dilate
from ..optim.loop import optimize
from ..plots import plot_log
from ..raybank import RayBank
from ..render.rays import render_rays
from ..render.views import layer_channels, render_camera
from ..scene import build_integrator, load_scene, write_scene

PREVIEW_VIEWS = 3


def load_recorded(record, path=None):
    """The dataset a run's ``config.json`` record names, loaded as the fit loaded it (format, holdout,
    downscale factor); ``path``: another folder, with the same holdout and factor."""
    same = path is None or os.path.abspath(path) == record.get("path")
    return load_dataset(path or record.get("path"), record.get("format", "auto") if same else "auto",
                        record.get("holdout", 8), record.get("factor"))


class FittedRun:
    """A fitting run folder: its dataset, fields and integrator properties."""

    def __init__(self, run_dir, dataset=None):
        self.dir = run_dir
        scene = os.path.join(run_dir, "scene.xml")
        if not os.path.isfile(scene):
            raise ValueError(f"{run_dir}: not a fitted run (no scene.xml); run scripts/train.py first")
        config = os.path.join(run_dir, "config.json")
        try:
            with open(config) as f:
                self.config = json.load(f)
        except OSError as e:
            raise ValueError(f"{config}: cannot read the run's settings ({e.strerror})") from None
        except ValueError as e:
            raise ValueError(f"{config}: not valid JSON ({e})") from None
        if not isinstance(self.config, dict):
            raise ValueError(f"{config}: must hold a JSON object of settings")
        record = self.config.get("dataset") or {}
        record = record if isinstance(record, dict) else {"path": record}
        try:
            self.dataset = load_recorded(record, dataset)
        except DatasetError as e:
            raise ValueError(f"{run_dir}: its dataset cannot be loaded ({e}); pass --dataset") from None
        base = load_scene(scene).integrator()
        self.fields = dict(base.fields)
        self.space = base.space
        self.properties = base.properties()

    def integrator(self, fields=None, **properties):
        """A ``voldis`` integrator over this run's fields (plus ``fields``) with changed properties."""
        return build_integrator({**self.fields, **(fields or {})}, {**self.properties, **properties})

    def foreground_box(self, margin=0.1, threshold_alpha=1e-2):
        """Scene-space box around where the full and background fields differ (the object's
        disentangled volume: vertices of the full field at least ``threshold_alpha`` opaque per voxel
        whose raw density the background does not share), grown by ``margin`` of its size and two
        voxels; the whole field box if they never differ."""
        full, bg = self.fields["full"], self.fields["bg"]
        voxel = np.max(np.abs(np.diag(full.to_world)[:3]) / (np.array(full.shape) - 1))
        local = full.density_vertices(density_raw_for_alpha(threshold_alpha, voxel, full.density_scale))
        pts = local @ full.to_world[:3, :3].T + full.to_world[:3, 3]
        if len(pts):
            a = np.array(full.lookup(from_numpy(mi.Point3f, local))[0])
            b = np.array(bg.lookup(from_numpy(mi.Point3f, pts @ bg.world_to_local[:3, :3].T +
                                              bg.world_to_local[:3, 3]))[0])
            pts = pts[np.abs(a - b) > 1e-3]
        if not len(pts):
            pts = np.array([[0, 0, 0], [1, 1, 1]], np.float64) @ full.to_world[:3, :3].T + full.to_world[:3, 3]
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        pad = margin * (hi - lo) + 2 * voxel
        return lo - pad, hi + pad

    def foreground_centre_world(self):
        lo, hi = self.foreground_box(margin=0.0)
        return self.space.to_world_np(0.5 * (lo + hi)[None])[0]

    def pixels_near_object(self, dilation):
        """Flat pixel indices (training views, row-major) within the object masks dilated by
        ``dilation`` of the image diagonal; None (all pixels) when the dataset has no masks."""
        ds = self.dataset
        if ds.masks is None:
            return None
        near = dilate(ds.masks[ds.train], diagonal_pixels(dilation, ds.size))
        return np.flatnonzero(near.reshape(-1)).astype(np.uint32)


def edit_field(lo, hi, resolution, density_raw=-30.0, color_raw=0.0, channels=3, density_scale=1.0):
    """Plugin dict of a new dense field over the scene-space box [lo, hi] (``resolution`` vertices along
    its longest side), constant raw density and colour."""
    x, y, z = shape_for(lo, hi, resolution)
    return field_dict(np.full((z, y, x, 1), density_raw, np.float32), np.full((z, y, x, channels), color_raw,
                                                                                np.float32),
                      box_transform(lo, hi), density_scale)


def residual_field(run, resolution, init_alpha, init_color):
    """A ``radiance_field`` over the object's box, faintly opaque (``init_alpha`` per half voxel) and
    of raw colour ``init_color``, with the full field's density scale."""
    lo, hi = run.foreground_box()
    full = run.fields["full"]
    voxel = float(np.max((hi - lo) / (resolution - 1)))
    raw = density_raw_for_alpha(init_alpha, 0.5 * voxel, full.density_scale)
    return mi.load_dict(edit_field(lo, hi, resolution, density_raw=raw, color_raw=init_color,
                                   density_scale=full.density_scale))


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
        o, d, color, mask, _ = self.bank.batch(rng, n, self.pool)
        out = render_rays(self.integrator, o, d, from_numpy(mi.Float, rng.random(n, np.float32)), self.layers)
        loss = self.loss_fn(out, color, mask)
        return loss, {"samples": float(dr.sum(out["evaluated"])[0])}


class TaskOutput:
    """What a task writes into its staging folder ``stage`` (RUN/<task>.partial, swapped into place as
    RUN/<task> when the task is done; see :func:`mi_voldis.tasks.run_task`)."""

    def __init__(self, run, task, settings, stage, final=None):
        self.run, self.task, self.settings, self.dir = run, task, settings, stage
        self.final = final or stage  # the folder the stage becomes
        write_json(os.path.join(self.dir, "config.json"), {**settings.to_dict(), "task": task})
        self.checkpoint = Checkpoint(os.path.join(self.dir, "checkpoints", "last.npz"))

    def write_scene(self, fields, **properties):
        """The edited scene: scene.xml with the run's integrator properties changed by ``properties``
        and a sensor per held-out view; of ``fields``, those the task changed are written here, the
        run's own are referred to in the run's folder (by relative path)."""
        ds = self.run.dataset
        shared = {role: os.path.join(self.run.dir, "scene.xml") for role, f in fields.items()
                  if self.run.fields.get(role) is f}
        return write_scene(self.dir, fields, {**self.run.properties, **properties},
                           [ds.cameras[v] for v in ds.test], shared=shared, final=self.final)

    def write_views(self, integrator, views=None, main="composite", extra=()):
        """Layered EXR and PNG previews of held-out views; returns {view: layers}."""
        ds = self.run.dataset
        views = list(ds.test if views is None else views)
        renders = {}
        layers = tuple(dict.fromkeys(("composite", "full", "bg", "fg", main) + tuple(extra)))
        for v in views:
            out = render_camera(integrator, ds.cameras[v], layers)
            renders[v] = out
            write_layers(self.dir, f"view{v:03d}", layer_channels(out, main),
                         [lay for lay in ("full", "bg", "fg", "res") if lay in out], camera=ds.cameras[v],
                         pngs=len(renders) <= PREVIEW_VIEWS, title=self.task)
        return renders

    def finish(self, metrics, log=None):
        """Write the metrics (and the optimisation log with its plot)."""
        if log:
            plot_log(os.path.join(self.dir, "loss.png"), log, f"{self.task}: loss against time")
            write_json(os.path.join(self.dir, "log.json"), log)
        write_json(os.path.join(self.dir, "metrics.json"), {**metrics, "peak_rss_mib": peak_rss_mib()})


def run_optimisation(output, problem, adam, desc, progress=True, final_ratio=0.1):
    """Optimise ``problem`` for the task's ``steps`` with checkpoints in ``output`` every
    ``checkpoint_every`` steps, resumable after a crash or kill -9 (``resume``)."""
    settings = output.settings
    start, log = 0, []
    if settings.resume:
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

    optimize(problem, adam, steps=settings.steps, start=start, final_ratio=final_ratio, log=log, desc=desc,
             checkpoint=save, checkpoint_every=settings.checkpoint_every, progress=progress)
    return log
