"""LLFF datasets: ``poses_bounds.npy`` with ``images_K/`` (or ``images/``) and optional object masks.

``poses_bounds.npy`` holds N x 17 numbers per view: a 3x5 matrix (rotation columns [down, right,
back], camera position, and [H, W, focal] of the ORIGINAL images) and the near/far bounds. The
focal length is rescaled to the size of the images actually read. Object masks: SPIn-NeRF's layout
(:func:`mask_paths`: ``images_K/label/`` for training views, ``images_K/test_label/`` for the test
views photographed without the object, whose photos are then the ground-truth background) or
``masks/NAME.*`` (white = object); views without a mask train the full field only. Effect masks (the
object's shadow, :class:`~mi_voldis.data.types.Dataset`): ``effects/NAME.*`` (white). A forward-facing
rig gets NDC with NeRF's near plane 0.75 x the smallest depth bound; another rig a world box.
"""
import os

import numpy as np

from .conventions import camera_from_intrinsics, llff_to_mitsuba, mitsuba_to_llff, rigid_error
from .images import (
    alpha_note,
    check_sizes,
    is_linear,
    list_images,
    mask_folder_paths,
    read_effects,
    read_image,
    read_masks,
)
from .scene_box import NEAR_FRACTION, capture_box
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


def mask_paths(root, folder, paths):
    """(mask rule, per image its training mask or None, per image its test mask or None), or None when
    the dataset has no masks. SPIn-NeRF: ``<folder>/label/`` holds the training views' masks (any
    nonzero value is the object) and ``<folder>/test_label/`` marks where the object stood in the test
    views, taken without it; else ``masks/`` (white = object). Files match the images by stem."""
    label, test_label = os.path.join(folder, "label"), os.path.join(folder, "test_label")
    if os.path.isdir(label) or os.path.isdir(test_label):
        return "nonzero", _by_stem(label, paths), _by_stem(test_label, paths)
    given = mask_folder_paths(root, paths)
    return None if given is None else ("white", given, [None] * len(paths))


def _by_stem(folder, paths):
    if not os.path.isdir(folder):
        return [None] * len(paths)
    files = {os.path.splitext(f)[0]: f for f in os.listdir(folder)}
    stems = (os.path.splitext(os.path.basename(p))[0] for p in paths)
    return [os.path.join(folder, files[s]) if s in files else None for s in stems]


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
    images = [read_image(p, background=None) for p in paths]
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
    notes = alpha_note(paths)
    split = np.array(["test" if holdout and k % holdout == 0 else "train" for k in range(len(names))])
    masks = masked = backgrounds = split_from = None
    found = mask_paths(root, folder, paths)
    if found is not None:
        rule, train_paths, test_paths = found
        is_test = np.array([p is not None for p in test_paths])
        both = [k for k, (m, t) in enumerate(zip(train_paths, test_paths)) if m is not None and t is not None]
        if both:  # test_label/ wins, as in SPIn-NeRF's own layout, where label/ may hold every view
            notes.append(f"{len(both)} views have a mask in both label/ and test_label/ (the first: {names[both[0]]}): "
                         "they are test views, photographed without the object (their photos are the background's "
                         "ground truth); their label/ masks are not used")
        if is_test.any():  # SPIn-NeRF: the test views are the photos taken without the object
            split = np.where(is_test, "test", "train")
            split_from = os.path.dirname(next(p for p in test_paths if p is not None)) + "/ (SPIn-NeRF's test views)"
            backgrounds = np.where(is_test[:, None, None, None], np.stack(images), np.nan).astype(np.float32)
            notes.append(f"{int(is_test.sum())} views with test_label/ masks are test views: their photos are "
                         "the background without the object")
        given = [t if t is not None else m for m, t in zip(train_paths, test_paths)]
        masks, masked = read_masks(given, rule, (h, w), notes)
    effects = read_effects(mask_folder_paths(root, paths, kind="effects") or [], (h, w), masks)
    box, _ = capture_box(cameras, None, path, notes, near=NEAR_FRACTION * bounds.min(), far=bounds.max() * 1.5)
    ds = Dataset(name=os.path.basename(os.path.normpath(root)), root=root, names=names,
                 images=np.stack(images), cameras=cameras, split=split, box=box, masks=masks, masked=masked,
                 effects=effects, near_far=bounds, backgrounds=backgrounds,
                 meta={"format": "llff", "image_folder": folder, "notes": notes, "split_from": split_from,
                       "color_space": "linear (encoded with the sRGB curve)" if is_linear(paths[0]) else "sRGB"})
    return ds


def write_llff(root, cameras, bounds, folder="images"):
    """Write ``poses_bounds.npy`` for Mitsuba cameras (images go in ``root/folder`` by the caller)."""
    rows = []
    for cam, (near, far) in zip(cameras, bounds):
        if abs(cam.principal[0]) > 1e-9 or abs(cam.principal[1]) > 1e-9:
            raise ValueError("LLFF poses assume a centred principal point")
        rows.append(np.concatenate([mitsuba_to_llff(cam.to_world, cam.height, cam.width, cam.focal).ravel(),
                                    [near, far]]))
    np.save(os.path.join(root, "poses_bounds.npy"), np.array(rows))
