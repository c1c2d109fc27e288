"""Masks from two views (the benchmark's masks section): IoU against exact coverage, and removal with them.

    python -m mi_voldis.bench.masks RUN OUT

RUN: a finished fit of a ground-truth dataset kept with ``--keep-checkpoints``. Two training views are
given their ground-truth masks (:func:`given_views`: a rule of the rig, not of the results);
:func:`mi_voldis.masks3d.make_masks` writes masks for every view from them through RUN's full field;
OUT receives ``metrics.json`` (per-view IoU against the exact coverage > 0.5), the masks, a copy of the
dataset that reads them (``data/``), and the removal fitted with them
(:mod:`mi_voldis.bench.strategies` with the default ``bg_strategy``), scored with the true masks.
"""
import json
import os

import numpy as np

ORTHOGONAL = 90.0  # degrees between the two given views' directions to the scene when the rig allows it


def given_views(ds):
    """The first training view, and the training view that sees the rig's common target (the point
    nearest every optical axis) from the direction closest to :data:`ORTHOGONAL` degrees away from the
    first's (on a forward-facing rig: the widest baseline)."""
    from ..data.scene_box import look_at_point
    train = list(ds.train)
    target = look_at_point([ds.cameras[v] for v in train])
    way = {v: np.asarray(ds.cameras[v].to_world)[:3, 3] - target for v in train}
    way = {v: w / np.linalg.norm(w) for v, w in way.items()}
    a = train[0]
    angle = {v: np.degrees(np.arccos(np.clip(way[v] @ way[a], -1, 1))) for v in train[1:]}
    return a, min(angle, key=lambda v: abs(angle[v] - ORTHOGONAL))


def masked_copy(dataset, masks, out):
    """A folder that is ``dataset`` (symbolic links) but for its ``masks/``, which is ``masks``."""
    os.makedirs(out, exist_ok=True)
    for name in os.listdir(dataset):
        if name != "masks":
            os.symlink(os.path.join(os.path.abspath(dataset), name), os.path.join(out, name))
    os.symlink(os.path.abspath(masks), os.path.join(out, "masks"))
    return out


def main(argv=None):
    from .strategies import helper_arguments
    run, out = helper_arguments(argv, "masks")
    from ..data import load_dataset
    from ..fit.config import FitConfig
    from ..io.images import write_png
    from ..io.run_folder import write_json
    from ..masks3d import make_masks
    from ..metrics import iou
    from .strategies import main as refit
    with open(os.path.join(run, "config.json")) as f:
        record = json.load(f)["dataset"]
    ds = load_dataset(record["path"], record["format"], record["holdout"])
    os.makedirs(os.path.join(out, "given"), exist_ok=True)
    given = {}
    for v in given_views(ds):
        path = os.path.join(out, "given", ds.names[v])
        write_png(path, np.where(ds.masks[v], 255, 0).astype(np.uint8))
        given[ds.names[v]] = path
    summary = make_masks(record["path"], run, os.path.join(out, "masks"), given, progress=False)
    data = os.path.join(out, "data")
    if not os.path.isdir(data):
        masked_copy(record["path"], os.path.join(out, "masks"), data)
    made = load_dataset(data, record["format"], record["holdout"])
    truth = ds.coverage > 0.5 if ds.coverage is not None else ds.masks
    per_view = {ds.names[v]: iou(made.masks[v], truth[v]) for v in range(len(ds.names))}
    others = [ds.names[v] for v in range(len(ds.names)) if ds.names[v] not in given]
    refit([run, FitConfig().bg_strategy, os.path.join(out, "removal"), data])
    write_json(os.path.join(out, "metrics.json"), {
        "given": list(given), "iou_mean": float(np.nanmean([per_view[n] for n in others])),
        "iou_min": float(np.nanmin([per_view[n] for n in others])), "per_view": per_view, "make_masks": summary})


if __name__ == "__main__":
    main()
