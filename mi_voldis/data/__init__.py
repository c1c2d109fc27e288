"""Datasets: loaders for LLFF, transforms.json and COLMAP captures, returning a typed :class:`Dataset`."""
import os

import numpy as np

from .colmap import load_colmap, model_folder
from .llff import load_llff
from .transforms_json import load_transforms
from .types import Dataset, DatasetError

__all__ = ["Dataset", "DatasetError", "FORMATS", "load_dataset"]


LOADERS = {"llff": load_llff, "transforms": load_transforms, "colmap": load_colmap}
FORMATS = ("auto", *LOADERS)


def load_dataset(root, fmt="auto", holdout=8, factor=None):
    """Load a dataset folder. ``fmt``: 'llff', 'transforms', 'colmap' or 'auto' (transforms.json when
    present, else poses_bounds.npy, else a COLMAP sparse model). ``holdout``: every k-th view is a test
    view unless the files give a split. ``factor``: read the images downscaled by K (``images_K/``;
    for LLFF without it, the most downscaled folder there is)."""
    if not os.path.isdir(root):
        raise DatasetError(f"{root}: no such dataset folder")
    has_json = any(os.path.isfile(os.path.join(root, f)) for f in
                   ("transforms.json", "transforms_train.json", "transforms_test.json"))
    has_llff = os.path.isfile(os.path.join(root, "poses_bounds.npy"))
    if fmt == "auto":
        fmt = "transforms" if has_json else "llff" if has_llff else "colmap" if model_folder(root) else None
        if fmt is None:
            raise DatasetError(f"{root}: neither transforms.json, poses_bounds.npy nor sparse/0/cameras.bin found")
    if fmt not in LOADERS:
        raise DatasetError(f"unknown dataset format '{fmt}' (expected auto, {', '.join(LOADERS)})")
    if not (isinstance(holdout, int) and holdout >= 0):
        raise DatasetError(f"{root}: holdout must be 0 (no test views) or a positive k, got {holdout}")
    if factor is not None and not (isinstance(factor, int) and factor >= 1):
        raise DatasetError(f"{root}: the downscale factor must be a whole number >= 1, got {factor}")
    ds = LOADERS[fmt](root, holdout=holdout, factor=factor)
    check(ds)
    ds.meta["factor"] = factor
    return ds


def check(ds):
    """Checks that need the whole dataset, made before any work: training views exist, and every
    camera has a field of view in (0, 180) degrees and finite pose."""
    if len(ds.train) == 0:
        raise DatasetError(f"{ds.root}: no training views ({len(ds.test)} views, all held out for testing)")
    for name, c in zip(ds.names, ds.cameras):
        if not (np.isfinite(c.fov_x) and 0 < c.fov_x < 180):
            raise DatasetError(f"{ds.root}: view '{name}' has a field of view of {c.fov_x} degrees "
                               "(must be in (0, 180))")
        if not np.all(np.isfinite(c.to_world)):
            raise DatasetError(f"{ds.root}: view '{name}' has a non-finite camera pose")
