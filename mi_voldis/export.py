"""Render a ``voldis`` scene's sensors into layered EXRs and sRGB PNG previews."""
import os

import drjit as dr
import mitsuba as mi
import numpy as np

from .io.exr import write_exr
from .io.images import contact_sheet, depth_to_uint8, display_to_linear_premultiplied, display_to_uint8, write_png

PREVIEW_LAYERS = ("full", "bg", "fg")


def render_channels(scene, sensor=0, spp=None, seed=0):
    """Render one sensor; returns ``{channel name: (H, W) float32}`` with the EXR names
    (``R, G, B, A, depth.Z, full.R, ...``) of the ``voldis`` integrator's outputs, colours as the
    fields hold them (display-encoded)."""
    integrator = scene.integrator()
    if not hasattr(integrator, "exr_layers"):
        raise ValueError("the scene's integrator is not 'voldis'")
    sensor = scene.sensors()[sensor] if isinstance(sensor, int) else sensor
    with dr.suspend_grad():
        image = np.array(mi.render(scene, sensor=sensor, spp=spp or 0, seed=seed), dtype=np.float32)
    names = ["R", "G", "B"]
    if mi.has_flag(sensor.film().flags(), mi.FilmFlags.Alpha):
        names.append("coverage")  # the film's own alpha (ray hit a box); ours is the AOV "A"
    names += integrator.aov_names()
    if image.shape[2] != len(names):
        raise RuntimeError(f"rendered {image.shape[2]} channels, expected {len(names)} ({names})")
    return {name: image[..., k] for k, name in enumerate(names) if name != "coverage"}


def previews(channels, layers):
    """uint8 previews: main image, each layer's colour (premultiplied, over black) and the depth."""
    out = {"composite": display_to_uint8(np.stack([channels[c] for c in "RGB"], axis=-1))}
    for layer in layers:
        out[layer] = display_to_uint8(np.stack([channels[f"{layer}.{c}"] for c in "RGB"], axis=-1))
    out["depth"] = depth_to_uint8(channels["depth.Z"], channels["A"])
    return out


def linear_channels(channels):
    """The same channels with every layer's colour converted to premultiplied linear light."""
    out = dict(channels)
    for prefix, alpha in [("", "A")] + [(f"{lay}.", f"{lay}.A") for lay in ("full", "bg", "fg", "res")]:
        if f"{prefix}R" in channels:
            rgb = np.stack([channels[f"{prefix}{c}"] for c in "RGB"], axis=-1)
            lin = display_to_linear_premultiplied(rgb, channels[alpha])
            for k, c in enumerate("RGB"):
                out[f"{prefix}{c}"] = lin[..., k]
    return out


def write_layers(directory, stem, channels, layers=PREVIEW_LAYERS):
    """Write ``<stem>.exr`` (every channel, colours in linear light), ``<stem>_<layer>.png`` previews
    and a contact sheet ``<stem>_sheet.png`` (main, layers, depth). Returns the EXR path."""
    os.makedirs(directory, exist_ok=True)
    exr = os.path.join(directory, f"{stem}.exr")
    write_exr(exr, linear_channels(channels))
    images = previews(channels, [lay for lay in layers if f"{lay}.R" in channels])
    for name, image in images.items():
        write_png(os.path.join(directory, f"{stem}_{name}.png"), image)
    write_png(os.path.join(directory, f"{stem}_sheet.png"), contact_sheet(list(images.values())))
    return exr


def render_scene_files(scene, directory, spp=None, size=None, cameras=None, prefix="view"):
    """Render every sensor of ``scene`` (or, given, each ``(name, Camera)`` of ``cameras``) to
    ``directory``; ``size`` = (width, height) overrides the films. Returns the EXR paths."""
    if cameras is not None:
        sensors = [(name, mi.load_dict(cam.sensor_dict(spp or 1))) for name, cam in cameras]
    else:
        sensors = [(f"{prefix}{k:03d}", s) for k, s in enumerate(scene.sensors())]
    if size is not None:
        for _, sensor in sensors:
            params = mi.traverse(sensor)
            params["film.size"] = mi.ScalarVector2u(*size)
            params.update()
    return [write_layers(directory, name, render_channels(scene, sensor, spp)) for name, sensor in sensors]
