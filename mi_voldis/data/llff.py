"""LLFF datasets: ``poses_bounds.npy`` with ``images_K/`` (or ``images/``) and optional object masks.

``poses_bounds.npy`` holds N x 17 numbers per view: a 3x5 matrix (rotation columns [down, right,
back], camera position, and [H, W, focal] of the ORIGINAL images) and the near/far bounds. The
focal length is rescaled to the size of the images actually read. Object masks are read from
``images_K/label/NAME.png`` (SPIn-NeRF: any nonzero value is the object) or ``masks/NAME.*`` (white =
object), matched by file name. The scene is forward-facing: fields live in NDC space with NeRF's
near plane 0.75 x the smallest depth bound.
"""
import os

import numpy as np

from .conventions import camera_from_intrinsics, llff_to_mitsuba, mitsuba_to_llff, rigid_error
from .images import check_masks, check_sizes, list_images, read_image, read_mask
from .scene_box import NEAR_FRACTION, ndc_box
from .types import Dataset, DatasetError


def image_folder(root, factor=None):
    """``images_<factor>`` when given, else the most downsampled ``images_K``, else ``images``."""
    if factor is not None:
        folder = os.path.join(root, f"images_{factor}" if factor != 1 else "images")
        if not os.path.isdir(folder):
            raise DatasetError(f"{folder}: no such image folder")
        return folder
    ks = sorted((int(d[7:]) for d in os.listdir(root) if d.startswith("images_") and d[7:].isdigit()), reverse=True)
    for name in [f"images_{k}" for k in ks] + ["images"]:
        if os.path.isdir(os.path.join(root, name)):
            return os.path.join(root, name)
    raise DatasetError(f"{root}: no images/ or images_K/ folder next to poses_bounds.npy")


def mask_paths(root, folder, names):
    """Mask file per image, or None when the dataset has no masks."""
    label = os.path.join(folder, "label")
    if os.path.isdir(label):
        return [os.path.join(label, n) for n in names], "nonzero"
    masks = os.path.join(root, "masks")
    if os.path.isdir(masks):
        by_stem = {os.path.splitext(f)[0]: f for f in os.listdir(masks)}
        return [os.path.join(masks, by_stem.get(os.path.splitext(n)[0], n)) for n in names], "white"
    return None, None


def load_llff(root, factor=None, holdout=8):
    path = os.path.join(root, "poses_bounds.npy")
    try:
        data = np.load(path)
    except Exception as e:
        raise DatasetError(f"{path}: cannot read poses ({type(e).__name__}: {e})") from None
    if data.ndim != 2 or data.shape[1] != 17:
        raise DatasetError(f"{path}: expected an N x 17 array, got shape {data.shape}")
    if not np.all(np.isfinite(data)):
        bad = np.flatnonzero(~np.isfinite(data).all(axis=1))
        raise DatasetError(f"{path}: non-finite pose or bounds for view(s) {bad.tolist()}")
    folder = image_folder(root, factor)
    names = list_images(folder)
    if len(names) != len(data):
        raise DatasetError(f"{path}: {len(data)} poses but {len(names)} images in {folder}")
    paths = [os.path.join(folder, n) for n in names]
    images = [read_image(p) for p in paths]
    check_sizes(images, paths)
    h, w = images[0].shape[:2]
    poses = data[:, :15].reshape(-1, 3, 5)
    cameras = []
    for k, pose in enumerate(poses):
        if rigid_error(llff_to_mitsuba(pose)) > 1e-3:
            raise DatasetError(f"{path}: pose of view {k} ({names[k]}) is not a rigid rotation")
        h0, w0, f0 = pose[:, 4]
        if abs(h0 / w0 - h / w) > 0.01:
            raise DatasetError(f"{path}: view {k} was posed for {w0:.0f}x{h0:.0f}, whose aspect ratio "
                               f"differs from the {w}x{h} images in {folder}")
        cameras.append(camera_from_intrinsics(llff_to_mitsuba(pose), w, h, f0 * w / w0))
    bounds = data[:, 15:17]
    masks = None
    mpaths, rule = mask_paths(root, folder, names)
    if mpaths is not None:
        masks = [read_mask(p, rule) for p in mpaths]
        check_masks(masks, mpaths, (h, w))
        masks = np.stack(masks)
    split = np.array(["test" if holdout and k % holdout == 0 else "train" for k in range(len(names))])
    near = NEAR_FRACTION * bounds.min()
    return Dataset(name=os.path.basename(os.path.normpath(root)), root=root, names=names,
                   images=np.stack(images), cameras=cameras, split=split,
                   box=ndc_box(cameras, near, bounds.max() * 1.5), masks=masks, near_far=bounds,
                   meta={"format": "llff", "image_folder": folder})


def write_llff(root, cameras, bounds, folder="images"):
    """Write ``poses_bounds.npy`` for Mitsuba cameras (images go in ``root/folder`` by the caller)."""
    rows = []
    for cam, (near, far) in zip(cameras, bounds):
        if abs(cam.principal[0]) > 1e-9 or abs(cam.principal[1]) > 1e-9:
            raise ValueError("LLFF poses assume a centred principal point")
        rows.append(np.concatenate([mitsuba_to_llff(cam.to_world, cam.height, cam.width, cam.focal).ravel(),
                                    [near, far]]))
    np.save(os.path.join(root, "poses_bounds.npy"), np.array(rows))
