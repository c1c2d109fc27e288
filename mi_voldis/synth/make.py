"""Render a dataset with ground truth from a Mitsuba XML scene and its rig description (NAME.json).

Per view: the image (Mitsuba's path tracer), the object's exact visible coverage (everything black,
the object emitting 1, direct visibility only, box filter) and the binary mask from it (coverage >
0.5), the ground-truth background (object removed, with its shadow and reflections), and on test
views the ground truth with the object moved by the rig's stated transform. Writes transforms.json
(keys of :mod:`mi_voldis.data.transforms_json`) and, for forward-facing rigs, poses_bounds.npy.
Deterministic for a seed.

``layout='spinnerf'`` writes SPIn-NeRF's removal-benchmark layout instead (LLFF): the first
:data:`SPINNERF_TEST_SHARE` of the views by name photographed without the object (the ground truth)
with ``images_4/test_label/`` marking where it stood, the rest with the object and its masks in
``images_4/label/`` (255 = object), and ``poses_bounds.npy`` for all views from one rig.
"""
import json
import os
import shutil

import drjit as dr
import mitsuba as mi
import numpy as np

from ..data.conventions import mitsuba_to_opengl
from ..data.llff import write_llff
from ..io.images import linear_to_uint8, write_png
from ..io.limits import check_entries, check_memory
from ..io.run_folder import check_output, scene_files, staged
from ..progress import progress_iter
from ..transforms import compose, to_scalar_transform
from . import rigs, variants

PASSES = ("image", "coverage", "background", "moved")
LAYOUTS = ("transforms", "spinnerf")
SPINNERF_TEST_SHARE = 0.4  # SPIn-NeRF: 40 of 100 views are taken after the object was carried away
SPINNERF_FOLDER = "images_4"


def load_rig(scene_path):
    path = os.path.splitext(scene_path)[0] + ".json"
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        raise ValueError(f"{path}: cannot read the scene's rig description ({e})") from None


def make_cameras(rig, views, width, height):
    cam = rig["cameras"]
    if cam["type"] == "orbit":
        return rigs.orbit(views, cam["target"], cam["radius"], cam["elevation_deg"], cam["fov_deg"], width, height)
    if cam["type"] == "forward":
        return rigs.forward_grid(views, cam["centre"], cam["target"], cam["spread"], cam["fov_deg"], width, height)
    if cam["type"] == "path":
        if views != len(cam["positions"]):
            raise ValueError(f"the rig is a path of {len(cam['positions'])} cameras: --views cannot make it {views}")
        return rigs.path(cam["positions"], cam["targets"], cam["fov_deg"], width, height)
    raise ValueError(f"unknown camera rig type '{cam['type']}' (orbit, forward or path)")


def forward_facing(rig):
    """Whether the rig faces one way (LLFF's poses_bounds.npy and NDC apply): a forward grid, or a path
    that says so."""
    cam = rig["cameras"]
    return cam["type"] == "forward" or (cam["type"] == "path" and bool(cam.get("forward", False)))


def _sensor(width, height, spp):
    return (f'<sensor type="perspective" id="sensor"><float name="fov" value="40"/><string name="fov_axis" value="x"/>'
            f'<float name="near_clip" value="1e-3"/>'
            f'<sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>'
            f'<film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="{height}"/>'
            f'<string name="pixel_format" value="rgb"/><rfilter type="box"/></film></sensor>')


class _Renderer:
    """One loaded scene variant whose sensor is moved from view to view (kernels are reused)."""

    def __init__(self, root, width, height, spp):
        xml = variants.to_string(root).replace("</scene>", _sensor(width, height, spp) + "</scene>")
        self.scene = mi.load_string(xml)
        self.params = mi.traverse(self.scene)

    def render(self, camera, seed):
        self.params["sensor.to_world"] = to_scalar_transform(camera.to_world)
        self.params["sensor.x_fov"] = float(camera.fov_x)
        self.params.update()
        with dr.suspend_grad():
            return np.array(mi.render(self.scene, seed=seed), dtype=np.float32)[..., :3]


def object_centre(root, prefix):
    scene = mi.load_string(variants.to_string(root))
    boxes = [s.bbox() for s in scene.shapes() if s.id().startswith(prefix)]
    lo = np.min([np.array(b.min) for b in boxes], axis=0)
    hi = np.max([np.array(b.max) for b in boxes], axis=0)
    return 0.5 * (lo + hi)


def depth_bounds(root, cameras, width, height):
    """Per-view (near, far) depth bounds from rendered distances (1st and 99.9th percentiles)."""
    renderer = _Renderer(variants.with_integrator(root, "depth"), width, height, 4)
    bounds = []
    for k, cam in enumerate(cameras):
        z = renderer.render(cam, k)[..., 0]
        z = z[np.isfinite(z) & (z > 0)]
        bounds.append((np.percentile(z, 1.0), np.percentile(z, 99.9)))
    return np.array(bounds)


def make_dataset(scene_path, out, views=None, resolution=None, spp=None, seed=0, holdout=8, progress=True,
                 scene_folder=None, layout="transforms"):
    """Render the dataset of ``scene_path`` into ``out`` (see the module docstring); returns ``out``.
    ``scene_folder``: a folder copied into the dataset as ``scene/`` (e.g. a generated scene);
    ``layout``: 'transforms' (with every ground truth) or 'spinnerf'. ``out`` may not be, hold or lie
    inside the scene's files."""
    if layout not in LAYOUTS:
        raise ValueError(f"unknown dataset layout '{layout}' (expected {' or '.join(LAYOUTS)})")
    inputs = [(p, "scene file") for p in scene_files(scene_path) + [os.path.splitext(scene_path)[0] + ".json"]]
    inputs += [(scene_folder, "scene folder")] if scene_folder else []
    check_output(out, inputs, program="make_dataset")
    rig = load_rig(scene_path)
    root = variants.parse(scene_path)
    prefix = rig.get("object_prefix", "object")
    variants.check_object(root, prefix, scene_path)
    views = views or rig["views"]
    width, height = resolution or rig["resolution"]
    spp = spp or rig["spp"]
    mi.file_resolver().prepend(os.path.dirname(os.path.abspath(scene_path)))

    check_size("--res" if resolution else os.path.splitext(scene_path)[0] + ".json", width, height, spp)
    check_seed(seed, views)

    cameras = make_cameras(rig, views, width, height)
    split = ["test" if holdout and k % holdout == 0 else "train" for k in range(views)]
    mv = rig["moved"]
    moved_matrix = compose(mv.get("scale", 1.0), tuple(mv["rotate"]) if "rotate" in mv else None,
                           mv.get("translate", (0, 0, 0)), object_centre(root, prefix))
    scenes = {"image": root, "coverage": variants.coverage_only(root, prefix),
              "background": variants.without_object(root, prefix),
              "moved": variants.moved(root, prefix, moved_matrix)}

    if layout == "spinnerf":
        split = ["train"] * views  # no moved ground truth
        cameras = spinnerf_order(cameras)
    with staged(out, inputs=inputs, made_by="make_dataset") as tmp:
        if scene_folder is not None:
            shutil.copytree(scene_folder, os.path.join(tmp, "scene"))
        _render_views(tmp, scene_path, scenes, cameras, split, width, height, spp, seed, progress)
        if layout == "spinnerf":
            _spinnerf(tmp, cameras, depth_bounds(scenes["image"], cameras, width, height))
            return out
        frames = []
        for k, (cam, name) in enumerate(zip(cameras, _names(views))):
            frame = {"file_path": f"images/{name}", "transform_matrix": mitsuba_to_opengl(cam.to_world).tolist(),
                     "split": split[k], "object_mask_path": f"masks/{name}", "coverage_path": f"coverage/{name}",
                     "background_path": f"backgrounds/{name}"}
            if split[k] == "test":
                frame["moved_path"] = f"moved/{name}"
            frames.append(frame)
        meta = {"camera_angle_x": float(np.radians(cameras[0].fov_x)), "w": width, "h": height,
                "scene": os.path.basename(scene_path), "seed": seed, "spp": spp,
                "moved_transform": moved_matrix.tolist(), "frames": frames}
        if forward_facing(rig):
            bounds = depth_bounds(scenes["image"], cameras, width, height)
            write_llff(tmp, cameras, bounds)
            meta.update(forward_facing=True, near=float(bounds[:, 0].min()), far=float(bounds[:, 1].max()))
        else:
            meta.update(forward_facing=False, aabb=rig["aabb"])
        with open(os.path.join(tmp, "transforms.json"), "w") as f:
            json.dump(meta, f, indent=1)
    return out


# Memory of one view per pixel: the path tracer's film, the rendered image, its NumPy copies and the
# written PNG's arrays. Datasets of 512^2 to 2048^2 pixels (any spp: Mitsuba's path tracer is one fused
# kernel) grew by 146 bytes per pixel; 192 leaves a margin.
DATASET_BYTES = 192
FILM_CHANNELS = 5  # the largest film a pass renders: R, G, B, alpha and the filter weight
SEED_STRIDE = 1_000_003  # the renders' seeds: seed * SEED_STRIDE + pass * views + view


def check_size(source, width, height, spp):
    """Refuse a dataset whose views cannot be rendered, before any is (:mod:`mi_voldis.io.limits`):
    Mitsuba's wavefront (a sample per pixel and spp) and the film (pixels x channels) are Dr.Jit
    arrays; the memory is that of one view. ``source``: the flag or file that set the size."""
    check_entries(f"{source}: a {width}x{height} view at {spp} spp", width * height * max(spp, FILM_CHANNELS))
    check_memory(f"{source}: a {width}x{height} dataset", width * height * DATASET_BYTES)


def check_seed(seed, views):
    """Every render's seed (:data:`SEED_STRIDE`) must be a 32-bit number, as Mitsuba takes it."""
    top = (2 ** 32 - 1 - len(PASSES) * views) // SEED_STRIDE
    if not 0 <= seed <= top:
        raise ValueError(f"--seed must be from 0 to {top} for {views} views (each render's seed, seed x "
                         f"{SEED_STRIDE} + view, is a 32-bit number), got {seed}")


def spinnerf_tests(n):
    """Indices of the rig's object-free test views: :data:`SPINNERF_TEST_SHARE` of ``n``, spread evenly
    over the rig (as a re-shot trajectory is) rather than one end of it."""
    return [int(k) for k in np.unique(np.round(np.linspace(0, n - 1, int(round(SPINNERF_TEST_SHARE * n)))))]


def spinnerf_order(cameras):
    """The rig's cameras with the test views (:func:`spinnerf_tests`) first."""
    tests = spinnerf_tests(len(cameras))
    return [cameras[k] for k in tests + [k for k in range(len(cameras)) if k not in tests]]


def _spinnerf(folder, cameras, bounds):
    """Rearrange the rendered passes into SPIn-NeRF's layout (see the module docstring)."""
    names = _names(len(cameras))
    tests = len(spinnerf_tests(len(cameras)))
    target = os.path.join(folder, SPINNERF_FOLDER)
    for sub in ("label", "test_label"):
        os.makedirs(os.path.join(target, sub))
    for k, name in enumerate(names):
        photo = "backgrounds" if k < tests else "images"
        os.replace(os.path.join(folder, photo, name), os.path.join(target, name))
        os.replace(os.path.join(folder, "masks", name),
                   os.path.join(target, "test_label" if k < tests else "label", name))
    for sub in ("images", "masks", "coverage", "backgrounds", "moved"):
        shutil.rmtree(os.path.join(folder, sub))
    write_llff(folder, cameras, bounds)


def _names(views):
    return [f"view_{k:03d}.png" for k in range(views)]


def _render_views(folder, scene_path, scenes, cameras, split, width, height, spp, seed, progress):
    """Every pass of every view into ``folder``: images, coverage and masks, backgrounds, moved."""
    views = len(cameras)
    for sub in ("images", "masks", "coverage", "backgrounds", "moved"):
        os.makedirs(os.path.join(folder, sub))
    names = _names(views)
    for p, kind in enumerate(PASSES):
        renderer = _Renderer(scenes[kind], width, height, spp)
        todo = [k for k in range(views) if kind != "moved" or split[k] == "test"]
        for k in progress_iter(todo, f"{os.path.basename(scene_path)}: {kind}", progress):
            img = renderer.render(cameras[k], seed * SEED_STRIDE + p * views + k)
            if kind == "coverage":
                cov = np.round(np.clip(img.mean(axis=2), 0.0, 1.0) * 65535).astype(np.uint16)
                write_png(os.path.join(folder, "coverage", names[k]), cov)
                write_png(os.path.join(folder, "masks", names[k]), np.where(cov > 65535 / 2, 255, 0).astype(np.uint8))
            else:
                sub = {"image": "images", "background": "backgrounds", "moved": "moved"}[kind]
                write_png(os.path.join(folder, sub, names[k]), linear_to_uint8(img))
