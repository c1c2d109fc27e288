"""transforms.json datasets (Blender / instant-ngp / nerfstudio), with object masks and ground truth.

Top level: ``camera_angle_x`` (Blender) or ``fl_x`` [, ``fl_y``, ``cx``, ``cy``, ``w``, ``h``]
(pixels); optional ``aabb`` ([[x0, y0, z0], [x1, y1, z1]], the scene box), ``forward_facing``
(bool; otherwise detected from the camera layout), ``background_color`` (RGB over which RGBA
images are composited; default white, Blender's convention), ``moved_transform`` (4x4 world-space
matrix of the ``moved_path`` ground truth). Per frame: ``file_path`` (relative to the JSON file,
with or without extension), ``transform_matrix`` (camera-to-world, OpenGL axes), optional ``split``
('train' / 'test'), ``object_mask_path`` (white = object), ``coverage_path``, ``background_path``
(the scene without the object) and ``moved_path``. Without ``object_mask_path``, masks come from a
``masks/`` folder with the images' file stems. ``transforms_train.json`` + ``transforms_test.json``
(or ``_val``) may replace one file; they give the split.
"""
import json
import os

import numpy as np

from ..space import SceneBox
from .conventions import camera_from_intrinsics, opengl_to_mitsuba, rigid_error
from .images import IMAGE_EXTENSIONS, check_masks, check_sizes, has_alpha, read_coverage, read_image, read_mask
from .scene_box import is_forward_facing, ndc_box, world_box
from .types import Dataset, DatasetError

# Frame keys read elsewhere with another meaning: refusing them beats guessing.
AMBIGUOUS_FRAME_KEYS = {
    "mask_path": "nerfstudio's 'mask_path' marks pixels to ignore; object masks go in 'object_mask_path'",
    "fl_x": "per-frame intrinsics are not supported; give them once at the top level",
    "fl_y": "per-frame intrinsics are not supported; give them once at the top level",
    "camera_angle_x": "per-frame intrinsics are not supported; give them once at the top level",
    "cx": "per-frame intrinsics are not supported; give them once at the top level",
    "cy": "per-frame intrinsics are not supported; give them once at the top level",
}
SPLIT_FILES = (("transforms_train.json", "train"), ("transforms_test.json", "test"), ("transforms_val.json", "test"))


def json_files(root):
    """[(path, split or None)] of the transforms files in ``root``."""
    single = os.path.join(root, "transforms.json")
    if os.path.isfile(single):
        return [(single, None)]
    files = [(os.path.join(root, f), s) for f, s in SPLIT_FILES if os.path.isfile(os.path.join(root, f))]
    if {s for _, s in files} == {"test"} and len(files) == 2:  # both test and val: keep test
        files = files[:1]
    if any(f.endswith("transforms_test.json") for f, _ in files):
        files = [(f, s) for f, s in files if not f.endswith("transforms_val.json")]
    if not files:
        raise DatasetError(f"{root}: no transforms.json or transforms_train.json")
    return files


def _load_json(path):
    try:
        with open(path) as f:
            meta = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        raise DatasetError(f"{path}: cannot read JSON ({e})") from None
    if not isinstance(meta, dict) or not isinstance(meta.get("frames"), list) or not meta["frames"]:
        raise DatasetError(f"{path}: expected an object with a non-empty 'frames' list")
    return meta


def _resolve(base, rel, what, path):
    """Path of ``rel`` relative to the JSON's folder; tries image extensions when it has none."""
    p = os.path.normpath(os.path.join(base, rel))
    if os.path.isfile(p):
        return p
    if not os.path.splitext(p)[1]:
        for ext in IMAGE_EXTENSIONS:
            if os.path.isfile(p + ext):
                return p + ext
    raise DatasetError(f"{path}: {what} '{rel}' not found (looked for {p})")


def _intrinsics(meta, path, width, height):
    """(fx, cx, cy) in pixels for images of the given size."""
    w = meta.get("w", width)
    h = meta.get("h", height)
    if (w, h) != (width, height):
        raise DatasetError(f"{path}: says images are {w}x{h} but they are {width}x{height}")
    fx = None
    if "fl_x" in meta:
        fx = float(meta["fl_x"])
        fy = float(meta.get("fl_y", fx))
        if abs(fx - fy) > 1e-3 * fx:
            raise DatasetError(f"{path}: fl_x = {fx} and fl_y = {fy} differ; non-square pixels are not supported")
    if "camera_angle_x" in meta:
        angle = float(meta["camera_angle_x"])
        if not 0 < angle < np.pi:
            raise DatasetError(f"{path}: camera_angle_x must be in (0, pi) radians, got {angle}")
        fa = 0.5 * width / np.tan(0.5 * angle)
        if fx is not None and abs(fa - fx) > 1e-3 * fx:
            raise DatasetError(f"{path}: camera_angle_x gives a focal length of {fa:.3f} px but fl_x is "
                               f"{fx:.3f}; the intrinsics are ambiguous")
        fx = fa
    if fx is None:
        raise DatasetError(f"{path}: no intrinsics (camera_angle_x or fl_x)")
    if not (np.isfinite(fx) and fx > 0):
        raise DatasetError(f"{path}: the focal length must be a positive number of pixels, got {fx}")
    return fx, float(meta.get("cx", 0.5 * width)), float(meta.get("cy", 0.5 * height))


def load_transforms(root, holdout=8):
    files = json_files(root)
    metas = [(_load_json(p), p, s) for p, s in files]
    top = metas[0][0]
    background = np.asarray(top.get("background_color", (1.0, 1.0, 1.0)), np.float32)
    frames = []
    for meta, path, split in metas:
        for k, frame in enumerate(meta["frames"]):
            for key, why in AMBIGUOUS_FRAME_KEYS.items():
                if key in frame:
                    raise DatasetError(f"{path}: frame {k} has '{key}': {why}")
            for key in ("file_path", "transform_matrix"):
                if key not in frame:
                    raise DatasetError(f"{path}: frame {k} has no '{key}'")
            frames.append((frame, path, split or frame.get("split")))
    base = {path: os.path.dirname(path) for _, path, _ in metas}
    names, paths, images, cameras, splits = [], [], [], [], []
    for k, (frame, path, split) in enumerate(frames):
        p = _resolve(base[path], frame["file_path"], "image", path)
        names.append(os.path.basename(p))
        paths.append(p)
        images.append(read_image(p, background))
    check_sizes(images, paths)
    h, w = images[0].shape[:2]
    fx, cx, cy = _intrinsics(top, metas[0][1], w, h)
    for k, (frame, path, split) in enumerate(frames):
        m = np.asarray(frame["transform_matrix"], dtype=np.float64)
        if m.shape not in ((4, 4), (3, 4)) or not np.all(np.isfinite(m)):
            raise DatasetError(f"{path}: frame {k} ({names[k]}) has a non-finite or malformed transform_matrix")
        to_world = opengl_to_mitsuba(m)
        if rigid_error(to_world) > 1e-3:
            raise DatasetError(f"{path}: frame {k} ({names[k]}) transform_matrix is not a rigid motion")
        cameras.append(camera_from_intrinsics(to_world, w, h, fx, cx, cy))
        if split not in (None, "train", "test"):
            raise DatasetError(f"{path}: frame {k} has split '{split}' (expected 'train' or 'test')")
        splits.append(split)
    if any(s is None for s in splits):
        splits = ["test" if holdout and k % holdout == 0 else "train" for k in range(len(frames))]
    masks = _masks(root, frames, base, paths, (h, w))
    ds = Dataset(name=os.path.basename(os.path.normpath(root)), root=root, names=names, images=np.stack(images),
                 cameras=cameras, split=np.array(splits), box=None, masks=masks,
                 meta={"format": "transforms", "files": [p for p, _ in files]})
    if has_alpha(paths[0]):  # RGBA composited over a known colour: what rays see beyond the scene
        ds.meta["background_color"] = background.tolist()
    ds.coverage = _optional(frames, base, "coverage_path", read_coverage, (h, w))
    ds.backgrounds = _optional(frames, base, "background_path", lambda p: read_image(p, background), (h, w))
    ds.moved = _optional(frames, base, "moved_path", lambda p: read_image(p, background), (h, w))
    if "moved_transform" in top:
        ds.moved_transform = np.asarray(top["moved_transform"], np.float64)
    ds.box = _box(top, cameras, metas[0][1])
    if "aabb" in top:
        ds.meta["aabb"] = True  # a bounded scene: fitting keeps its world box
    if ds.box.kind == "ndc":
        ds.near_far = np.array([[float(top["near"]), float(top["far"])]])
    return ds


def _masks(root, frames, base, paths, shape):
    if any("object_mask_path" in f for f, _, _ in frames):
        mpaths = []
        for k, (frame, path, _) in enumerate(frames):
            if "object_mask_path" not in frame:
                raise DatasetError(f"{path}: frame {k} has no 'object_mask_path' while others do")
            mpaths.append(_resolve(base[path], frame["object_mask_path"], "mask", path))
    elif os.path.isdir(os.path.join(root, "masks")):
        folder = os.path.join(root, "masks")
        by_stem = {os.path.splitext(f)[0]: f for f in os.listdir(folder)}
        mpaths = [os.path.join(folder, by_stem.get(os.path.splitext(os.path.basename(p))[0],
                                                   os.path.basename(p))) for p in paths]
    else:
        return None
    masks = [read_mask(p, "white") for p in mpaths]
    check_masks(masks, mpaths, shape)
    return np.stack(masks)


def _optional(frames, base, key, reader, shape):
    """Per-view ground truth where frames have ``key``; NaN for the others; None if none has it."""
    if not any(key in f for f, _, _ in frames):
        return None
    out = []
    for frame, path, _ in frames:
        if key in frame:
            img = reader(_resolve(base[path], frame[key], key, path))
            if img.shape[:2] != shape:
                raise DatasetError(f"{path}: {frame[key]} is {img.shape[1]}x{img.shape[0]}, the images are "
                                   f"{shape[1]}x{shape[0]}")
            out.append(img)
        else:
            out.append(None)
    like = next(o for o in out if o is not None)
    return np.stack([o if o is not None else np.full_like(like, np.nan) for o in out])


def _box(top, cameras, path):
    forward = top.get("forward_facing")
    if forward is None:
        forward = is_forward_facing(cameras)
    if forward:
        near = float(top.get("near", 0.0)) or None
        far = float(top.get("far", 0.0)) or None
        if near is None or far is None:
            raise DatasetError(f"{path}: a forward-facing transforms.json needs 'near' and 'far' depth bounds")
        return ndc_box(cameras, near, far)
    if "aabb" in top:
        aabb = np.asarray(top["aabb"], np.float64)
        if aabb.shape != (2, 3) or not np.all(aabb[1] > aabb[0]):
            raise DatasetError(f"{path}: 'aabb' must be [[x0, y0, z0], [x1, y1, z1]] with x1 > x0 etc.")
        return SceneBox("world", aabb[0], aabb[1])
    return world_box(cameras)
