"""The Python API: a fitted run, rendered and edited from code.

    import mi_voldis
    run = mi_voldis.load_run("out/demo/run/tabletop")
    moved = run.edit("transform", {"matrix": [[1, 0, 0, 0.2], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]})
    layers = moved.render(view=run.dataset.test[0])   # {"composite": (H, W, 4), ..., "depth": (H, W)}

Layers are those written to EXR (:mod:`mi_voldis.compositing`): premultiplied RGBA in linear light
(``linear=False``: sRGB-encoded, for display), ``fg`` the object such that full = fg over bg, and the
depth (distance along the ray, world units). Wrong arguments raise ``ValueError`` naming the argument.
"""
import json
import os

import numpy as np

from .cameras import Camera
from .compositing import composite_channels
from .io.images import linear_to_srgb
from .render.views import layer_channels, render_camera
from .scene import load_scene

LAYERS = ("composite", "full", "bg", "fg")


def _render(integrator, camera, layers, linear):
    if isinstance(layers, str):
        layers = (layers,)
    unknown = [layer for layer in layers if layer not in LAYERS]
    if unknown:
        raise ValueError(f"layers: unknown layer {unknown[0]!r} (expected some of {', '.join(LAYERS)})")
    raw = render_camera(integrator, camera, tuple(dict.fromkeys(("composite", "full", "bg", "fg") + tuple(layers))))
    ch = composite_channels(layer_channels(raw))
    out = {}
    for layer in layers:
        prefix = "" if layer == "composite" else f"{layer}."
        rgb = np.stack([ch[f"{prefix}{c}"] for c in "RGB"], axis=-1)
        rgb = rgb if linear else linear_to_srgb(rgb).astype(np.float32)
        out[layer] = np.concatenate([rgb, ch[f"{prefix}A"][..., None]], axis=-1)
    out["depth"] = ch["depth.Z"]
    return out


class _Renders:
    def _camera(self, camera, view):
        if camera is not None:
            if not isinstance(camera, Camera):
                raise ValueError(f"camera: must be a mi_voldis.cameras.Camera (or give view=INDEX), got "
                                 f"{type(camera).__name__}")
            return camera
        ds = self.dataset
        if view is None:
            return ds.cameras[int(ds.test[0] if len(ds.test) else ds.train[0])]
        if isinstance(view, bool) or not isinstance(view, (int, np.integer)):
            raise ValueError(f"view: must be a view index (a whole number), got {view!r}")
        if not -len(ds.cameras) <= view < len(ds.cameras):
            raise ValueError(f"view: {view} is out of range (the dataset has {len(ds.cameras)} views)")
        return ds.cameras[int(view)]

    def render(self, camera=None, view=None, layers=LAYERS, linear=True):
        """{layer: (H, W, 4) premultiplied RGBA, "depth": (H, W)} from ``camera`` (a
        :class:`~mi_voldis.cameras.Camera`) or the dataset's view ``view`` (an index; default: the first
        test view). ``layers``: some of :data:`LAYERS` (or one of them)."""
        return _render(self.integrator(), self._camera(camera, view), layers, linear)


class Run(_Renders):
    """A fitted run folder (``scripts/train.py``): its dataset (``.dataset``), fields and integrator."""

    def __init__(self, path, dataset=None):
        from .tasks import FittedRun
        self._run = FittedRun(path, dataset)
        self.path = path

    @property
    def dataset(self):
        return self._run.dataset

    def integrator(self, **properties):
        return self._run.integrator(**properties)

    def edit(self, task, settings=None, out=None, progress=False):
        """Run ``task`` ('removal', 'transform', 'camouflage', 'nonneg', 'semantic') with ``settings``
        (its settings class from :mod:`mi_voldis.tasks.settings`, or a dict of values; NumPy arrays are
        accepted, e.g. a transform's 4x4 ``matrix``) into ``out``; returns the :class:`Edit`. By default
        ``out`` is RUN/<task>, or RUN/<task>_2, _3, ... where that exists: an edit never replaces an
        earlier one unless ``out`` names it. ``out`` may not be, hold or lie inside the run's files or
        its dataset."""
        from .tasks import SETTINGS, run_task
        if task not in SETTINGS:
            raise ValueError(f"task: unknown task {task!r} (expected one of {', '.join(SETTINGS)})")
        if settings is not None and not isinstance(settings, (dict, SETTINGS[task])):
            raise ValueError(f"settings: must be a dict of {task} settings or a {SETTINGS[task].__name__}, got "
                             f"{type(settings).__name__}")
        if out is None:
            out = free_folder(os.path.join(self.path, task))
        if isinstance(settings, dict):
            settings = {k: np.asarray(v).tolist() if isinstance(v, np.ndarray) else v for k, v in settings.items()}
        folder = run_task(self.path, task, settings, progress=progress, out=out)
        return Edit(folder, self.dataset)


class Edit(_Renders):
    """An edited scene (a task's output folder): ``.metrics``, ``.path``, and rendering."""

    def __init__(self, path, dataset):
        self.path, self.dataset = path, dataset
        with open(os.path.join(path, "metrics.json")) as f:
            self.metrics = json.load(f)
        self._integrator = None

    def integrator(self):
        if self._integrator is None:
            self._integrator = load_scene(os.path.join(self.path, "scene.xml")).integrator()
        return self._integrator


def free_folder(path):
    """``path``, or ``path_2``, ``path_3``, ... the first that neither exists nor is staged."""
    k, candidate = 1, path
    while os.path.lexists(candidate) or os.path.lexists(candidate + ".partial"):
        k += 1
        candidate = f"{path}_{k}"
    return candidate


def load_run(path, dataset=None):
    """The fitted run in folder ``path`` (its dataset reloaded as the fit saw it, or ``dataset``)."""
    return Run(path, dataset)
