"""transforms.json datasets (Blender / instant-ngp / nerfstudio), with object masks and ground truth.

Top level: ``camera_angle_x`` (Blender) or ``fl_x`` [, ``fl_y``, ``cx``, ``cy``, ``w``, ``h``]
(pixels, for images of ``w`` x ``h``), nerfstudio's ``camera_model`` (PINHOLE, OPENCV,
OPENCV_FISHEYE: the views are undistorted once with ``k1``..``k4``, ``p1``, ``p2``, read as nerfstudio
reads them, ``k4`` under OPENCV its r^8 term; views with ``fl_y`` != ``fl_x`` are resampled to square
pixels; :mod:`mi_voldis.data.lens`); every one of these may instead be given per frame. Optional: ``aabb``
([[x0, y0, z0], [x1, y1, z1]], the scene box; without it, RGBA views of a 360-degree layout give the box of
their alpha's visual hull, :func:`~mi_voldis.data.scene_box.silhouette_box`), ``forward_facing`` (bool;
otherwise detected from the camera layout), ``near`` / ``far`` (forward-facing depth bounds; estimated from
the points, or NeRF's default near plane 1, when absent), ``ply_file_path`` (sparse points in the frames'
world frame, as ns-process-data writes them: they give depth bounds and the box), ``applied_transform`` (the
3x4 matrix nerfstudio applied to COLMAP's world; kept in ``meta``), ``background_color`` (RGB over which RGBA
images are composited; default white, Blender's convention), ``moved_transform`` (4x4 world-space matrix of
the ``moved_path`` ground truth), ``applied_scale`` (kept in ``meta``),
``train_filenames`` / ``test_filenames`` (``val_filenames`` when there is no test list; paths as the
frames' ``file_path``: they give the split, as nerfstudio's dataparser reads them; frames in no list
are left out). Per frame: ``file_path`` (relative to
the JSON file, with or without extension), ``transform_matrix`` (camera-to-world, OpenGL axes),
optional ``split`` ('train' / 'test'), ``mask_path`` (nerfstudio's pixels to ignore: black = left out
of training, :attr:`~mi_voldis.data.types.Dataset.ignore`), ``object_mask_path`` (white = object), ``effect_mask_path``
(white = the object's shadow or reflection outside its mask, else ``effects/`` by file stem; views
without one have none), ``coverage_path``,
``background_path`` (the scene without the object) and ``moved_path``. Without
``object_mask_path``, masks come from a ``masks/`` folder with the images' file stems; views without
one train the full field only. ``transforms_train.json`` + ``transforms_test.json`` (or ``_val``) may
replace one file; they give the split. ``factor`` K (nerfstudio's downscale) reads ``images_K/NAME``
(masks from ``masks_K/`` when present, else resized) with the intrinsics scaled to match.
"""
import json
import os

import numpy as np

from .conventions import camera_from_intrinsics, opengl_to_mitsuba, rigid_error
from .images import (
    IMAGE_EXTENSIONS,
    check_sizes,
    has_alpha,
    is_linear,
    mask_folder_paths,
    read_alpha,
    read_coverage,
    read_effects,
    read_image,
    read_mask,
    read_masks,
)
from .images import _reduce as reduce_mask
from .lens import LensError, lens_from_opencv_keys
from .points import read_ply
from .scene_box import capture_box, silhouette_box
from .types import Dataset, DatasetError

INTRINSIC_KEYS = ("camera_model", "camera_angle_x", "fl_x", "fl_y", "cx", "cy", "w", "h",
                  "k1", "k2", "k3", "k4", "p1", "p2")
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
        with open(path, encoding="utf-8") as f:
            meta = json.load(f)
    except UnicodeDecodeError as e:
        raise DatasetError(f"{path}: not UTF-8 text, as JSON must be (byte {e.start}: {e.reason}); save it as "
                           "UTF-8") from None
    except (OSError, json.JSONDecodeError) as e:
        raise DatasetError(f"{path}: cannot read JSON ({e})") from None
    if not isinstance(meta, dict) or not isinstance(meta.get("frames"), list) or not meta["frames"]:
        raise DatasetError(f"{path}: expected an object with a non-empty 'frames' list")
    return meta


def _number(value, key, path, where=""):
    """``value`` as a float when it is a finite JSON number; else one line naming the file and key."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise DatasetError(f"{path}: {where}'{key}' must be a finite number, got {json.dumps(value)}")
    return float(value)


def _matrix(value, key, path, shapes, where=""):
    """``value`` as a float64 array of one of ``shapes`` with finite entries; else one line naming it."""
    try:
        m = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        m = None
    if m is None or m.shape not in shapes or not np.all(np.isfinite(m)):
        want = " or ".join("x".join(map(str, s)) for s in shapes)
        want = f"a list of {want} finite numbers" if len(shapes[0]) == 1 else f"a {want} matrix of finite numbers"
        got = "non-numeric" if m is None else "x".join(map(str, m.shape)) if m.shape not in shapes else "non-finite"
        raise DatasetError(f"{path}: {where}'{key}' must be {want}, got {got}")
    return m


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


def _lens(d, path, width, height, factor):
    """Pinhole intrinsics (fx, cx, cy) and a resampling function for views of ``d``'s intrinsics (the
    top level merged with a frame's own keys) read as ``width`` x ``height`` images."""
    w, h = d.get("w", width), d.get("h", height)
    scale = width / w
    if factor is None and (w, h) != (width, height):
        raise DatasetError(f"{path}: says images are {w}x{h} but they are {width}x{height}")
    if abs(h * scale - height) > 1.0:
        raise DatasetError(f"{path}: images of {width}x{height} are not {w}x{h} scaled by one factor")
    keys = dict(d)
    if "camera_angle_x" in d:
        angle = float(d["camera_angle_x"])
        if not 0 < angle < np.pi:
            raise DatasetError(f"{path}: camera_angle_x must be in (0, pi) radians, got {angle}")
        fa = 0.5 * w / np.tan(0.5 * angle)
        if "fl_x" in d and abs(fa - float(d["fl_x"])) > 1e-3 * fa:
            raise DatasetError(f"{path}: camera_angle_x gives a focal length of {fa:.3f} px but fl_x is "
                               f"{float(d['fl_x']):.3f}; the intrinsics are ambiguous")
        keys["fl_x"] = fa
    if "fl_x" not in keys:
        raise DatasetError(f"{path}: no intrinsics (camera_angle_x or fl_x)")
    keys.setdefault("cx", 0.5 * w)
    keys.setdefault("cy", 0.5 * h)
    try:
        lens = lens_from_opencv_keys(d.get("camera_model", "OPENCV"), keys, nerfstudio=True)
    except (LensError, TypeError, ValueError) as e:
        raise DatasetError(f"{path}: {e}") from None
    if not all(np.isfinite(v) and v > 0 for v in (lens.fx, lens.fy)):
        raise DatasetError(f"{path}: the focal length must be a positive number of pixels, got {lens.fx}")
    return lens.scaled(scale).undistorter(width, height)


def _image_path(root, base, frame, path, factor):
    """The frame's image; with ``factor`` K > 1, ``images_K/NAME`` beside the JSON (nerfstudio)."""
    if not factor or factor == 1:
        return _resolve(base, frame["file_path"], "image", path)
    folder = os.path.join(root, f"images_{factor}")
    if not os.path.isdir(folder):
        raise DatasetError(f"{folder}: no such image folder (--factor {factor} reads images_{factor}/)")
    return _resolve(folder, os.path.basename(frame["file_path"]), "image", path)


def load_transforms(root, holdout=8, factor=None):
    files = json_files(root)
    metas = [(_load_json(p), p, s) for p, s in files]
    top = metas[0][0]
    background = _matrix(top.get("background_color", (1.0, 1.0, 1.0)), "background_color", metas[0][1], ((3,),))
    if not np.all((background >= 0) & (background <= 1)):
        raise DatasetError(f"{metas[0][1]}: 'background_color' must be 3 numbers in [0, 1], got {background.tolist()}")
    background = background.astype(np.float32)
    frames = []
    for meta, path, split in metas:
        for k, frame in enumerate(meta["frames"]):
            if not isinstance(frame, dict):
                raise DatasetError(f"{path}: frame {k} must be an object with 'file_path' and 'transform_matrix'")
            for key in ("file_path", "transform_matrix"):
                if key not in frame:
                    raise DatasetError(f"{path}: frame {k} has no '{key}'")
            for key in ("file_path", "mask_path", "object_mask_path", "effect_mask_path", "coverage_path",
                        "background_path", "moved_path"):
                if key in frame and not (isinstance(frame[key], str) and frame[key]):
                    raise DatasetError(f"{path}: frame {k}: '{key}' must be a file path, got {json.dumps(frame[key])}")
            frames.append((frame, path, split or frame.get("split")))
    base = {path: os.path.dirname(path) for _, path, _ in metas}
    frames, listed = _split_lists(top, metas[0][1], frames, base)
    names, paths, images, cameras, splits = [], [], [], [], []
    for k, (frame, path, split) in enumerate(frames):
        p = _image_path(root, base[path], frame, path, factor)
        names.append(os.path.basename(p))
        paths.append(p)
        images.append(read_image(p, background))
    check_sizes(images, paths)
    h, w = images[0].shape[:2]
    lenses, resamplers = {}, []
    for frame, path, _ in frames:
        d = {key: (frame if key in frame else top)[key] for key in INTRINSIC_KEYS if key in frame or key in top}
        for key, value in d.items():
            if key != "camera_model":
                d[key] = _number(value, key, path, "frame " if key in frame else "")
        tag = json.dumps(d, sort_keys=True)
        if tag not in lenses:
            lenses[tag] = _lens(d, path, w, h, factor)
        resamplers.append(lenses[tag])
    images = [r[1](img) for r, img in zip(resamplers, images)]
    notes = []
    if any(r[1].__name__ != "_identity" for r in resamplers):
        notes.append(f"{len(frames)} views undistorted to pinhole cameras ({top.get('camera_model', 'OPENCV')} "
                     "lens model)")
    for k, (frame, path, split) in enumerate(frames):
        fx, cx, cy = resamplers[k][0]
        m = _matrix(frame["transform_matrix"], "transform_matrix", path, ((4, 4), (3, 4)), f"frame {k} ({names[k]}): ")
        to_world = opengl_to_mitsuba(m)
        if rigid_error(to_world) > 1e-3:
            raise DatasetError(f"{path}: frame {k} ({names[k]}) transform_matrix is not a rigid motion")
        cameras.append(camera_from_intrinsics(to_world, w, h, fx, cx, cy))
        if split not in (None, "train", "test"):
            raise DatasetError(f"{path}: frame {k} has split '{split}' (expected 'train' or 'test')")
        splits.append(split)
    split_from = (" and ".join(os.path.basename(p) for p, _ in files) if files[0][1] else
                  f"the frames' 'split' keys in {files[0][0]}")
    if any(s is None for s in splits):
        splits = ["test" if holdout and k % holdout == 0 else "train" for k in range(len(frames))]
        split_from = None
    if listed:
        notes.append(listed)
        split_from = f"the file lists in {files[0][0]} ({listed})"
    undistort = [r[1] for r in resamplers]
    masks, masked = _masks(root, frames, base, paths, (h, w), factor, undistort, notes)
    ignore = _ignore(root, frames, base, (h, w), factor, undistort, notes)
    effects = _effects(root, frames, base, paths, (h, w), factor, undistort, masks)
    ds = Dataset(name=os.path.basename(os.path.normpath(root)), root=root, names=names, images=np.stack(images),
                 cameras=cameras, split=np.array(splits), box=None, masks=masks, masked=masked, effects=effects,
                 ignore=ignore, meta={"format": "transforms", "files": [p for p, _ in files], "notes": notes,
                                      "split_from": split_from,
                       "color_space": "linear (encoded with the sRGB curve)" if is_linear(paths[0]) else "sRGB"})
    if any(has_alpha(p) for p in paths):  # RGBA composited over a known colour: what rays see beyond the scene
        ds.meta["background_color"] = background.tolist()
        notes.append(f"RGBA images composited over background_color {background.tolist()} (Blender's convention: "
                     "alpha 0 is the empty space around the scene)")
    ds.coverage = _optional(frames, base, "coverage_path", read_coverage, (h, w), undistort)
    ds.backgrounds = _optional(frames, base, "background_path", lambda p: read_image(p, background), (h, w), undistort)
    ds.moved = _optional(frames, base, "moved_path", lambda p: read_image(p, background), (h, w), undistort)
    if "moved_transform" in top:
        ds.moved_transform = _matrix(top["moved_transform"], "moved_transform", metas[0][1], ((4, 4),))
    if "applied_transform" in top:
        applied = np.eye(4)
        applied[:3, :4] = _matrix(top["applied_transform"], "applied_transform", metas[0][1], ((3, 4), (4, 4)))[:3, :4]
        ds.meta["applied_transform"] = applied.tolist()
    if "applied_scale" in top:
        ds.meta["applied_scale"] = _number(top["applied_scale"], "applied_scale", metas[0][1])
        if ds.meta["applied_scale"] <= 0:
            raise DatasetError(f"{metas[0][1]}: 'applied_scale' must be > 0, got {ds.meta['applied_scale']}")
    if "ply_file_path" in top:
        ds.points = read_ply(_resolve(base[metas[0][1]], top["ply_file_path"], "ply_file_path", metas[0][1]))
    ds.box, ds.near_far = _box(top, cameras, metas[0][1], ds.points, notes)
    if "aabb" in top:
        ds.meta["aabb"] = True  # a bounded scene: fitting keeps its world box
    elif "background_color" in ds.meta and ds.box.kind == "world":  # an object on an empty backdrop
        train = [k for k in ds.train if has_alpha(paths[k])]
        alphas = [undistort[k](read_alpha(paths[k])) for k in train]
        box = silhouette_box([cameras[k] for k in train], alphas, ds.box)
        if box is not None:
            ds.box = box
            ds.meta["silhouette_box"] = True  # fitting keeps it (scene_box.fitting_box)
            notes.append(f"scene box from the training views' alpha (their visual hull): "
                         f"{np.round(box.lo, 3).tolist()} to {np.round(box.hi, 3).tolist()}")
        else:
            notes.append("no scene box from the training views' alpha (their visual hull is empty, or reaches the "
                         "cameras' box): fitted in contracted space")
    return ds


def _split_lists(top, path, frames, base):
    """(frames, note): with nerfstudio's ``train_filenames`` / ``test_filenames`` (else
    ``val_filenames``), the frames they list with their split, the others left out; else unchanged."""
    lists = {s: top[f"{s}_filenames"] for s in ("train", "test", "val") if f"{s}_filenames" in top}
    if not lists:
        return frames, None
    if "test" in lists:
        lists.pop("val", None)
    key = lambda b, rel: os.path.splitext(os.path.normpath(os.path.join(b, str(rel))))[0]  # noqa: E731
    own = {key(base[p], f["file_path"]): k for k, (f, p, _) in enumerate(frames)}
    split = {}
    for name, files in lists.items():
        if not isinstance(files, list):
            raise DatasetError(f"{path}: '{name}_filenames' must be a list of image paths")
        for rel in files:
            k = own.get(key(os.path.dirname(path), rel))
            if k is None:
                raise DatasetError(f"{path}: '{name}_filenames' lists '{rel}', which no frame's file_path names")
            split[k] = "train" if name == "train" else "test"
    if "train" in lists:
        kept = [(f, p, split[k]) for k, (f, p, _) in enumerate(frames) if k in split]
        if all(s == "test" for _, _, s in kept):
            raise DatasetError(f"{path}: 'train_filenames' lists no frame that is not also a test frame")
    else:  # only an evaluation list: every other frame trains
        kept = [(f, p, split.get(k, "train")) for k, (f, p, _) in enumerate(frames)]
    names = " / ".join(f"{n}_filenames" for n in lists)
    left = len(frames) - len(kept)
    return kept, f"split from {names}" + (f"; {left} frames listed in neither are left out" if left else "")


def _ignore(root, frames, base, shape, factor, undistort, notes):
    """nerfstudio's ``mask_path`` (black = pixels to ignore; with ``factor`` K, ``masks_K/NAME`` when
    present, else reduced) undistorted as the images: (N, H, W) bool, True = ignore; None without any."""
    if not any("mask_path" in f for f, _, _ in frames):
        return None
    out = np.zeros((len(frames),) + tuple(shape), bool)
    for k, (frame, path, _) in enumerate(frames):
        if "mask_path" not in frame:
            continue
        rel = frame["mask_path"]
        folder = os.path.join(root, f"masks_{factor}") if factor and factor > 1 else None
        if folder and os.path.isfile(os.path.join(folder, os.path.basename(rel))):
            p = os.path.join(folder, os.path.basename(rel))
        else:
            p = _resolve(base[path], rel, "mask_path", path)
        keep = read_mask(p, "white")
        if factor and factor > 1:
            keep = reduce_mask(keep, shape)
        if keep.shape != tuple(shape):
            raise DatasetError(f"{p}: mask_path is {keep.shape[1]}x{keep.shape[0]} but the images are "
                               f"{shape[1]}x{shape[0]}")
        out[k] = ~undistort[k](keep, nearest=True)
    if out.all(axis=(1, 2)).any():
        k = int(np.flatnonzero(out.all(axis=(1, 2)))[0])
        raise DatasetError(f"{frames[k][1]}: frame {k}'s mask_path ignores every pixel")
    notes.append(f"mask_path: {100 * out.mean():.1f}% of the pixels are marked to ignore (black); training "
                 "leaves them out")
    return out


def _masks(root, frames, base, paths, shape, factor, undistort, notes):
    """Object masks (object_mask_path, else ``masks/`` by file stem; with ``factor`` K, ``masks_K/``
    when present), resized to the images when they are K times larger, undistorted as the images."""
    if any("object_mask_path" in f for f, _, _ in frames):
        mpaths = [_resolve(base[path], frame["object_mask_path"], "mask", path) if "object_mask_path" in frame
                  else None for frame, path, _ in frames]
    else:
        mpaths = mask_folder_paths(root, paths, factor)
        if mpaths is None:
            return None, None
    masks, masked = read_masks(mpaths, "white", shape, notes, resize=bool(factor and factor > 1))
    if masks is not None:
        masks = np.stack([u(m, nearest=True) for u, m in zip(undistort, masks)])
    return masks, masked


def _effects(root, frames, base, paths, shape, factor, undistort, masks):
    """Effect masks (``effect_mask_path``, else ``effects/`` by file stem), read and undistorted as the
    object masks, outside them; None when there are none."""
    if any("effect_mask_path" in f for f, _, _ in frames):
        epaths = [_resolve(base[path], frame["effect_mask_path"], "effect mask", path)
                  if "effect_mask_path" in frame else None for frame, path, _ in frames]
    else:
        epaths = mask_folder_paths(root, paths, factor, "effects") or []
    effects = read_effects(epaths, shape, masks, resize=bool(factor and factor > 1))
    if effects is None:
        return None
    return np.stack([u(m, nearest=True) for u, m in zip(undistort, effects)]) & ~masks


def _optional(frames, base, key, reader, shape, undistort):
    """Per-view ground truth where frames have ``key`` (undistorted as the images); NaN for the others;
    None if none has it."""
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
    out = [o if o is None else u(o) for o, u in zip(out, undistort)]
    like = next(o for o in out if o is not None)
    return np.stack([o if o is not None else np.full_like(like, np.nan) for o in out])


def _box(top, cameras, path, points, notes):
    """(scene box, near/far bounds or None): :func:`~mi_voldis.data.scene_box.capture_box`."""
    aabb = None
    if "aabb" in top:
        aabb = _matrix(top["aabb"], "aabb", path, ((2, 3),))
        if not np.all(aabb[1] > aabb[0]):
            raise DatasetError(f"{path}: 'aabb' must be [[x0, y0, z0], [x1, y1, z1]] with x1 > x0 etc.")
    near, far = (_number(top.get(key, 0.0), key, path) for key in ("near", "far"))
    if "forward_facing" in top and not isinstance(top["forward_facing"], bool):
        raise DatasetError(f"{path}: 'forward_facing' must be true or false, got {json.dumps(top['forward_facing'])}")
    return capture_box(cameras, points, path, notes, top.get("forward_facing"), near, far, aabb)
