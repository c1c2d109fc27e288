"""Render whole camera views through a ``voldis`` integrator into NumPy layers (evaluation, tasks)."""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..cameras import pixel_rays
from ..device import from_numpy
from .rays import render_rays

CHUNK = 1 << 16  # rays per launch


def render_camera(integrator, camera, layers=("composite", "full", "bg", "fg"), samples=None):
    """Layers of a :class:`~mi_voldis.cameras.Camera` through pixel centres (jitter 0.5):
    ``{layer: (rgb (H, W, 3), alpha (H, W), depth (H, W))}``, display-encoded colours, plus
    ``"fg_coverage"`` (H, W) with the ``fg`` layer and ``"evaluated"`` (H, W), the samples each pixel's
    ray evaluated (see :func:`mi_voldis.render.march.march`)."""
    py, px = np.mgrid[0:camera.height, 0:camera.width]
    o, d = pixel_rays(camera, px.ravel() + 0.5, py.ravel() + 0.5)
    out = {layer: ([], [], []) for layer in layers}
    coverage, evaluated = [], []
    with dr.suspend_grad():
        for s in range(0, len(o), CHUNK):
            oo, dd = from_numpy(mi.Point3f, o[s:s + CHUNK]), from_numpy(mi.Vector3f, d[s:s + CHUNK])
            res = render_rays(integrator, oo, dd, dr.full(mi.Float, 0.5, dr.width(oo)), layers, samples)
            for layer in layers:
                rgb, a, z = res[layer]
                out[layer][0].append(np.array(rgb).T)
                out[layer][1].append(np.array(a))
                out[layer][2].append(np.array(z))
            coverage.append(np.array(res["fg_coverage"]))
            evaluated.append(np.array(res["evaluated"]))
    h, w = camera.height, camera.width
    result = {layer: (np.concatenate(v[0]).reshape(h, w, 3), np.concatenate(v[1]).reshape(h, w),
                      np.concatenate(v[2]).reshape(h, w)) for layer, v in out.items()}
    result["evaluated"] = np.concatenate(evaluated).reshape(h, w)
    if "fg" in layers:
        result["fg_coverage"] = np.concatenate(coverage).reshape(h, w)
    return result


def layer_channels(layers, main="composite"):
    """Channel dict (``R, G, B, A, depth.Z, <layer>.R/G/B/A/Z``, ``fg.coverage``) of rendered layers,
    as the integrator's AOVs name them (display-encoded sums; :mod:`mi_voldis.compositing` turns them
    into the layers written to EXR); the main
    image is layer ``main`` plus the residual layer when there is one (as the integrator renders it)."""
    rgb, a, z = layers[main]
    if "res" in layers:
        rgb = rgb + layers["res"][0]
    channels = {"R": rgb[..., 0], "G": rgb[..., 1], "B": rgb[..., 2], "A": a, "depth.Z": z}
    for name in ("full", "bg", "fg", "res"):
        if name in layers:
            rgb, a, z = layers[name]
            channels.update({f"{name}.R": rgb[..., 0], f"{name}.G": rgb[..., 1], f"{name}.B": rgb[..., 2],
                             f"{name}.A": a, f"{name}.Z": z})
    if "fg_coverage" in layers:
        channels["fg.coverage"] = layers["fg_coverage"]
    return channels
