"""Render a ``voldis`` scene's sensors into layered EXRs (:mod:`mi_voldis.compositing`) and PNG previews."""
import os
import shlex
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

from .compositing import composite_channels, exr_header
from .io.exr import write_exr
from .io.images import contact_sheet, depth_to_uint8, linear_to_uint8, write_png

PREVIEW_LAYERS = ("full", "bg", "fg")
SHEET_LABELS = {"composite": "image", "full": "full scene", "bg": "background", "fg": "foreground (object)",
                "res": "light added", "depth": "depth"}


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


def previews(linear, layers, backdrop=None):
    """uint8 previews of composited channels (:func:`~mi_voldis.compositing.composite_channels`): the
    main image and each layer (premultiplied, over black, or with ``backdrop`` (linear RGB) over that:
    C + (1 - A) backdrop; sRGB-encoded) and the depth."""
    def over(prefix):
        rgb = np.stack([linear[f"{prefix}{c}"] for c in "RGB"], axis=-1)
        if backdrop is None:
            return linear_to_uint8(rgb)
        return linear_to_uint8(rgb + (1.0 - linear[f"{prefix}A"])[..., None] * np.asarray(backdrop, rgb.dtype))
    out = {"composite": over("")}
    for layer in layers:
        out[layer] = over(f"{layer}.")
    out["depth"] = depth_to_uint8(linear["depth.Z"], linear["A"])
    return out


def write_layers(directory, stem, channels, layers=PREVIEW_LAYERS, camera=None, command=None, pngs=True,
                 title=None):
    """Write ``<stem>.exr`` (composited channels, header with the camera and ``command``, by default
    this process's command line) and, with ``pngs``, ``<stem>_<layer>.png`` previews and a contact
    sheet ``<stem>_sheet.png`` (main, layers, depth; the main image captioned ``title``, e.g. a task's
    name, else "image"). ``channels``: the integrator's raw channels. Returns the EXR path."""
    os.makedirs(directory, exist_ok=True)
    exr = os.path.join(directory, f"{stem}.exr")
    linear = composite_channels(channels)
    write_exr(exr, linear, exr_header(camera, command or shlex.join([os.path.basename(sys.executable)] + sys.argv)))
    if pngs:
        images = previews(linear, [lay for lay in layers if f"{lay}.R" in linear])
        for name, image in images.items():
            write_png(os.path.join(directory, f"{stem}_{name}.png"), image)
        labels = [title if k == "composite" and title else SHEET_LABELS.get(k, k) for k in images]
        write_png(os.path.join(directory, f"{stem}_sheet.png"), contact_sheet(list(images.values()), labels=labels))
    return exr


def render_path(scene, directory, cameras, spp=None, layer="composite", fps=24, prefix="frame"):
    """Render ``cameras`` (a camera path) to ``directory/<prefix>_NNNN.exr`` and the ``layer``'s frames
    as a video (:func:`mi_voldis.video.write_video`: MP4, or GIF without imageio-ffmpeg). Returns
    (EXR paths, video path)."""
    from .video import write_video
    key = "" if layer == "composite" else f"{layer}."
    exrs, frames = [], []
    for k, cam in enumerate(cameras):
        raw = render_channels(scene, mi.load_dict(cam.sensor_dict(spp or 1)), spp)
        exrs.append(write_layers(directory, f"{prefix}_{k:04d}", raw, camera=cam, pngs=False))
        linear = composite_channels(raw)
        if f"{key}R" not in linear:
            raise ValueError(f"the scene renders no '{layer}' layer (it has {', '.join(PREVIEW_LAYERS)})")
        frames.append(linear_to_uint8(np.stack([linear[f"{key}{c}"] for c in "RGB"], axis=-1)))
    return exrs, write_video(os.path.join(directory, layer), frames, fps)


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
    cams = dict(cameras) if cameras is not None else {}
    return [write_layers(directory, name, render_channels(scene, sensor, spp), camera=cams.get(name))
            for name, sensor in sensors]
