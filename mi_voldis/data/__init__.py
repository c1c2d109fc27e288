"""Datasets: loaders for LLFF, transforms.json and COLMAP captures, returning a typed :class:`Dataset`."""
import os

import numpy as np

from .colmap import load_colmap, model_folder
from .llff import load_llff
from .transforms_json import load_transforms
from .types import Dataset, DatasetError

__all__ = ["Dataset", "DatasetError", "FORMATS", "check_rig", "load_dataset"]


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
    check_split(ds, holdout)
    ds.meta["factor"] = factor
    return ds


def pose_file(ds):
    """The file that holds the dataset's poses (what a message about them names)."""
    files = ds.meta.get("files") or [os.path.join(ds.root, "poses_bounds.npy")]
    return ds.meta.get("model", files[0])


def check(ds):
    """Checks that need the whole dataset, made before any work: training views exist, and every
    camera has a field of view in (0, 180) degrees and a finite pose. Cameras that all stand at one
    point (:func:`check_rig`, refused by a fit) and views with the same pose are noted."""
    if len(ds.train) == 0:
        raise DatasetError(f"{ds.root}: no training views ({len(ds.test)} views, all held out for testing)")
    for name, c in zip(ds.names, ds.cameras):
        if not (np.isfinite(c.fov_x) and 0 < c.fov_x < 180):
            raise DatasetError(f"{ds.root}: view '{name}' has a field of view of {c.fov_x} degrees "
                               "(must be in (0, 180))")
        if not np.all(np.isfinite(c.to_world)):
            raise DatasetError(f"{ds.root}: view '{name}' has a non-finite camera pose")
    notes = ds.meta.setdefault("notes", [])
    problem = _rig_problem(ds)
    if problem:
        notes.append(problem)
    if len(ds.cameras) < 2:
        return
    poses = np.stack([np.asarray(c.to_world, np.float64) for c in ds.cameras])
    scale = 1e-9 * max(1.0, float(np.abs(poses[:, :3, 3]).max()))
    seen, twins = {}, []
    for k, m in enumerate(np.round(poses / scale).astype(np.int64)):
        first = seen.setdefault(m.tobytes(), k)
        if first != k:
            twins.append(f"'{ds.names[k]}' = '{ds.names[first]}'")
    if twins and not problem:
        notes.append(f"{len(twins)} views have the pose of an earlier view ({', '.join(twins[:3])}"
                     f"{', ...' if len(twins) > 3 else ''}): they add no new viewpoint")


def _rig_problem(ds):
    """The line saying that the dataset's cameras all stand at one point, or None."""
    if len(ds.cameras) < 2:
        return None
    poses = np.stack([np.asarray(c.to_world, np.float64) for c in ds.cameras])
    centres = poses[:, :3, 3]
    scale = 1e-9 * max(1.0, float(np.abs(centres).max()))
    if np.linalg.norm(centres - centres[0], axis=1).max() > scale:
        return None
    same = "have one pose" if np.abs(poses - poses[0]).max() <= scale else "stand at one point"
    at = ", ".join(f"{v:.6g}" for v in centres[0])
    return (f"{pose_file(ds)}: all {len(poses)} cameras {same} ({at}): views from one point show no depth, so no "
            "radiance field can be fitted (are the poses those of the photos?)")


def check_rig(ds):
    """Refuses a dataset whose cameras all stand at one point (a panorama, or every pose the same: no
    parallax, so no depth to fit); loading only notes it, since such views can still be rendered or
    read. Called before a fit."""
    problem = _rig_problem(ds)
    if problem:
        raise DatasetError(problem)


def check_split(ds, holdout):
    """A split the dataset's files give makes ``holdout`` moot: a note says so when it is not the
    default 8 (nor 0, which make_masks passes for every view); a chosen k larger than the number of
    views is refused (view 0 alone would be held out, whatever k; the default 8 on a smaller dataset
    is that too, and allowed)."""
    given = ds.meta.get("split_from")
    if given and holdout not in (0, 8):
        ds.meta.setdefault("notes", []).append(f"holdout {holdout} is ignored: the split comes from {given}")
    elif not given and holdout > len(ds.names) and holdout != 8:
        raise DatasetError(f"{ds.root}: holdout {holdout} is more than the {len(ds.names)} views (every k-th view is "
                           f"held out; 0 holds none out, {len(ds.names)} holds out view 0 alone)")
