"""Datasets: loaders for LLFF and transforms.json captures, returning a typed :class:`Dataset`."""
import os

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
    if fmt == "transforms":
        return load_transforms(root, holdout)
    if fmt == "llff":
        return load_llff(root, factor, holdout)
    raise DatasetError(f"unknown dataset format '{fmt}' (expected auto, llff or transforms)")
