"""COLMAP sparse models: ``sparse/0/`` (or ``sparse/``) with ``cameras``, ``images`` and ``points3D``
as ``.bin`` or ``.txt``, and the photos in ``images/`` (``images_K/`` with ``factor`` K).

Read from COLMAP's documented formats (no pycolmap needed). Binary, little-endian:

* cameras.bin: u64 count; per camera i32 id, i32 model, u64 width, u64 height, f64 params[n(model)];
* images.bin: u64 count; per image i32 id, f64 qw qx qy qz, f64 tx ty tz, i32 camera id, the name
  (NUL-terminated), u64 n2d, then n2d x (f64 x, f64 y, i64 point id);
* points3D.bin: u64 count; per point i64 id, f64 xyz, u8 rgb, f64 error, u64 n, n x (i32, i32).

Text files hold the same, one camera or point per line, two lines per image (the second, the 2D
points, may be empty). A pose maps world to camera: x_cam = R(q) x + t, in OpenCV's camera axes (+x
right, +y down, +z forward); Mitsuba's camera frame flips x and y. Lenses with distortion are
undistorted once (:mod:`mi_voldis.data.lens`). Object masks: ``masks/`` by file stem (white = object);
effect masks (the object's shadow): ``effects/`` by file stem.
The points give each view's depth bounds (forward-facing captures) and the box.
"""
import os
import struct

import numpy as np

from ..transforms import quaternion_to_rotation
from .conventions import camera_from_intrinsics
from .images import alpha_note, check_sizes, is_linear, mask_folder_paths, read_effects, read_image, read_masks
from .lens import COLMAP_MODELS, LensError, lens_from_colmap
from .scene_box import capture_box
from .types import Dataset, DatasetError

CV_TO_MI = np.diag([-1.0, -1.0, 1.0, 1.0])


def model_folder(root):
    """The folder of the sparse model: ``sparse/0``, else ``sparse``; None when there is none."""
    for sub in (os.path.join("sparse", "0"), "sparse"):
        d = os.path.join(root, sub)
        if any(os.path.isfile(os.path.join(d, f"cameras.{ext}")) for ext in ("bin", "txt")):
            return d
    return None


class _Reader:
    def __init__(self, path):
        self.path = path
        with open(path, "rb") as f:
            self.data = f.read()
        self.pos = 0

    def take(self, fmt):
        size = struct.calcsize("<" + fmt)
        if self.pos + size > len(self.data):
            raise DatasetError(f"{self.path}: truncated at byte {self.pos}")
        out = struct.unpack_from("<" + fmt, self.data, self.pos)
        self.pos += size
        return out

    def name(self):
        end = self.data.find(b"\0", self.pos)
        if end < 0:
            raise DatasetError(f"{self.path}: truncated image name at byte {self.pos}")
        out = self.data[self.pos:end].decode("utf-8")
        self.pos = end + 1
        return out


def _cameras_bin(path):
    r, out = _Reader(path), {}
    for _ in range(r.take("Q")[0]):
        cam_id, model_id, width, height = r.take("iiQQ")
        if model_id not in COLMAP_MODELS:
            raise DatasetError(f"{path}: camera {cam_id} has unknown model id {model_id}")
        name, params = COLMAP_MODELS[model_id]
        out[cam_id] = (name, int(width), int(height), r.take("d" * len(params)))
    return out


def _images_bin(path):
    r, out = _Reader(path), []
    for _ in range(r.take("Q")[0]):
        image_id, *pose, cam_id = r.take("idddddddi")
        name = r.name()
        n2d = r.take("Q")[0]
        r.pos += 24 * n2d
        out.append((name, np.array(pose[:4]), np.array(pose[4:]), cam_id))
    return out


def _points_bin(path):
    r, pts = _Reader(path), []
    for _ in range(r.take("Q")[0]):
        values = r.take("qdddBBBd")
        pts.append(values[1:4])
        track = r.take("Q")[0]
        r.pos += 8 * track
    return np.array(pts, np.float64).reshape(-1, 3)


def _lines(path):
    with open(path) as f:
        return [line.rstrip("\n") for line in f if not line.startswith("#")]


def _cameras_txt(path):
    out = {}
    for line in _lines(path):
        w = line.split()
        if not w:
            continue
        try:
            out[int(w[0])] = (w[1], int(w[2]), int(w[3]), tuple(float(v) for v in w[4:]))
        except (ValueError, IndexError):
            raise DatasetError(f"{path}: malformed camera line '{line}'") from None
    return out


def _images_txt(path):
    lines, out = _lines(path), []
    # two lines per image; the second (its 2D points) may be empty, so pair lines, not words
    while lines and not lines[-1].strip():
        lines.pop()
    for k in range(0, len(lines), 2):
        w = lines[k].split()
        try:
            out.append((" ".join(w[9:]), np.array(w[1:5], np.float64), np.array(w[5:8], np.float64), int(w[8])))
        except (ValueError, IndexError):
            raise DatasetError(f"{path}: malformed image line '{lines[k]}'") from None
    return out


def _points_txt(path):
    rows = [line.split()[1:4] for line in _lines(path) if line.strip()]
    try:
        return np.array(rows, np.float64).reshape(-1, 3)
    except ValueError:
        raise DatasetError(f"{path}: malformed point lines") from None


def read_model(folder):
    """(cameras {id: (model, width, height, params)}, images [(name, qvec, tvec, camera id)],
    points (P, 3)) of a sparse model folder (binary files preferred when both exist)."""
    def pick(stem, binary, text):
        b, t = os.path.join(folder, stem + ".bin"), os.path.join(folder, stem + ".txt")
        if os.path.isfile(b):
            return binary(b)
        if os.path.isfile(t):
            return text(t)
        return None
    try:
        cams = pick("cameras", _cameras_bin, _cameras_txt)
        images = pick("images", _images_bin, _images_txt)
        points = pick("points3D", _points_bin, _points_txt)
    except OSError as e:
        raise DatasetError(f"{e.filename}: cannot read ({e.strerror})") from None
    if images is None:
        raise DatasetError(f"{folder}: no images.bin or images.txt beside the cameras")
    return cams, images, points


def load_colmap(root, holdout=8, factor=None):
    folder = model_folder(root)
    if folder is None:
        raise DatasetError(f"{root}: no sparse/0/cameras.bin (or .txt)")
    cams, records, points = read_model(folder)
    if not records:
        raise DatasetError(f"{folder}: the model has no registered images")
    records.sort(key=lambda r: r[0])
    image_dir = os.path.join(root, f"images_{factor}" if factor and factor > 1 else "images")
    if not os.path.isdir(image_dir):
        raise DatasetError(f"{image_dir}: no such image folder")
    paths = [os.path.join(image_dir, name) for name, *_ in records]
    images = [read_image(p, background=None) for p in paths]
    check_sizes(images, paths)
    h, w = images[0].shape[:2]
    undistorters, cameras, notes = {}, [], alpha_note(paths)
    for k, (name, q, t, cam_id) in enumerate(records):
        if cam_id not in cams:
            raise DatasetError(f"{folder}: image {name} refers to camera {cam_id}, which is not in the model")
        model, cw, ch, params = cams[cam_id]
        if cam_id not in undistorters:
            if abs(h / w - ch / cw) > 0.01:
                raise DatasetError(f"{folder}: camera {cam_id} is {cw}x{ch} but the images in {image_dir} are "
                                   f"{w}x{h}, another aspect ratio")
            try:
                undistorters[cam_id] = lens_from_colmap(model, params).scaled(w / cw).undistorter(w, h)
            except LensError as e:
                raise DatasetError(f"{folder}: camera {cam_id}: {e}") from None
        (fx, cx, cy), resample = undistorters[cam_id]
        images[k] = resample(images[k])
        world_to_cam = np.eye(4)
        world_to_cam[:3, :3], world_to_cam[:3, 3] = quaternion_to_rotation(q), t
        if not np.all(np.isfinite(world_to_cam)):
            raise DatasetError(f"{folder}: image {name} has a non-finite pose")
        cameras.append(camera_from_intrinsics(np.linalg.inv(world_to_cam) @ CV_TO_MI, w, h, fx, cx, cy))
    if any(r[1].__name__ != "_identity" for r in undistorters.values()):
        notes.append(f"{len(records)} views undistorted to pinhole cameras "
                     f"({', '.join(sorted({cams[c][0] for c in undistorters}))})")
    names = [os.path.basename(p) for p in paths]
    mpaths = mask_folder_paths(root, paths, factor)
    masks, masked = (None, None) if mpaths is None else read_masks(mpaths, "white", (h, w), notes, resize=bool(factor))
    if masks is not None:
        masks = np.stack([undistorters[r[3]][1](m, nearest=True) for r, m in zip(records, masks)])
    effects = read_effects(mask_folder_paths(root, paths, factor, "effects") or [], (h, w), masks, bool(factor))
    if effects is not None:
        effects = np.stack([undistorters[r[3]][1](m, nearest=True) for r, m in zip(records, effects)]) & ~masks
    split = np.array(["test" if holdout and k % holdout == 0 else "train" for k in range(len(names))])
    ds = Dataset(name=os.path.basename(os.path.normpath(root)), root=root, names=names, images=np.stack(images),
                 cameras=cameras, split=split, box=None, masks=masks, masked=masked, effects=effects, points=points,
                 meta={"format": "colmap", "model": folder, "image_folder": image_dir, "notes": notes,
                       "color_space": "linear (encoded with the sRGB curve)" if is_linear(paths[0]) else "sRGB"})
    ds.box, ds.near_far = capture_box(cameras, points, folder, notes)
    return ds


