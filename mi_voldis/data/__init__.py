"""Datasets: loaders for LLFF and transforms.json captures, returning a typed :class:`Dataset`."""
import os

import numpy as np

from .llff import load_llff
from .transforms_json import load_transforms
from .types import Dataset, DatasetError

__all__ = ["Dataset", "DatasetError", "load_dataset"]


def load_dataset(root, fmt="auto", holdout=8, factor=None):
    """Load a dataset folder. ``fmt``: 'llff', 'transforms' or 'auto' (transforms.json when present,
    else poses_bounds.npy). ``holdout``: every k-th view is a test view unless the files give a split.
    ``factor``: LLFF image downsampling folder (images_<factor>)."""
    if not os.path.isdir(root):
        raise DatasetError(f"{root}: no such dataset folder")
    has_json = any(os.path.isfile(os.path.join(root, f)) for f in
                   ("transforms.json", "transforms_train.json", "transforms_test.json"))
    has_llff = os.path.isfile(os.path.join(root, "poses_bounds.npy"))
    if fmt == "auto":
        fmt = "transforms" if has_json else "llff" if has_llff else None
        if fmt is None:
            raise DatasetError(f"{root}: neither transforms.json nor poses_bounds.npy found")
    if fmt not in ("transforms", "llff"):
        raise DatasetError(f"unknown dataset format '{fmt}' (expected auto, llff or transforms)")
    if not (isinstance(holdout, int) and holdout >= 0):
        raise DatasetError(f"{root}: holdout must be 0 (no test views) or a positive k, got {holdout}")
    ds = load_transforms(root, holdout) if fmt == "transforms" else load_llff(root, factor, holdout)
    check(ds)
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
