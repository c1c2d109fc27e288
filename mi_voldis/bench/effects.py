"""The object's shadow as an input (the benchmark's effects section): removal with effect masks.

    python -m mi_voldis.bench.effects RUN OUT

RUN: a finished fit of a ground-truth dataset kept with ``--keep-checkpoints``. Outside the object's mask
the photos differ from the ground-truth background where the object casts its shadow (or shows in a
mirror): :func:`effect_masks` marks those pixels, ``OUT/data`` is a copy of RUN's dataset that reads them
(``effect_mask_path``), and the background is fitted again from RUN's full field with the default
``bg_strategy``, without them (``OUT/without``) and with them (``OUT/with``,
:mod:`mi_voldis.bench.strategies`), both scored as the removal section scores (with the object masks).
OpenCV's Telea and Navier-Stokes inpaint each held-out view inside its dilated mask and its effect mask
beside them (the same input). OUT receives ``metrics.json``.
"""
import json
import os

import numpy as np

THRESHOLD = 0.04  # mean |photo - background| over RGB, both blurred (5x5 Gaussian, 1 px): above render noise


def effect_masks(images, backgrounds, masks, threshold=THRESHOLD):
    """(N, H, W) bool: pixels outside ``masks`` where the photos ``images`` differ from the ground-truth
    ``backgrounds`` (display-encoded, (N, H, W, 3)) by more than ``threshold`` after a light blur, with
    specks of a pixel or two removed (morphological opening)."""
    import cv2
    out = np.zeros(masks.shape, bool)
    for k, (image, background) in enumerate(zip(images, backgrounds)):
        if not np.isfinite(background).all():
            continue
        blur = [cv2.GaussianBlur(np.ascontiguousarray(x, np.float32), (5, 5), 1.0) for x in (image, background)]
        differs = (np.abs(blur[0] - blur[1]).mean(-1) > threshold) & ~masks[k]
        out[k] = cv2.morphologyEx(differs.astype(np.uint8), cv2.MORPH_OPEN, np.ones((3, 3), np.uint8)) > 0
    return out


def effect_copy(dataset, effects, names, out):
    """A folder that is the transforms.json dataset ``dataset`` (symbolic links) with ``effects`` (per
    view, in the order of its frames, named ``names``) in ``effects/`` and given to every frame as its
    ``effect_mask_path``."""
    from ..io.images import write_png
    os.makedirs(os.path.join(out, "effects"), exist_ok=True)
    for name in os.listdir(dataset):
        if name != "transforms.json" and not os.path.lexists(os.path.join(out, name)):
            os.symlink(os.path.join(os.path.abspath(dataset), name), os.path.join(out, name))
    with open(os.path.join(dataset, "transforms.json")) as f:
        meta = json.load(f)
    for frame, name, effect in zip(meta["frames"], names, effects):
        path = os.path.join("effects", os.path.splitext(name)[0] + ".png")
        write_png(os.path.join(out, path), (effect * 255).astype(np.uint8))
        frame["effect_mask_path"] = path
    with open(os.path.join(out, "transforms.json"), "w") as f:
        json.dump(meta, f, indent=1)
    return out


def main(argv=None):
    from .strategies import helper_arguments
    run, out = helper_arguments(argv, "effects")
    from ..data import load_dataset
    from ..fit.config import FitConfig
    from ..inpaint2d import inpainter
    from ..io.run_folder import write_json
    from ..metrics import dilate, psnr, score_dilation
    from .strategies import main as refit
    with open(os.path.join(run, "config.json")) as f:
        record = json.load(f)["dataset"]
    if record["format"] != "transforms":
        raise SystemExit(f"error: {run}: effect masks are written for transforms.json datasets only")
    ds = load_dataset(record["path"], record["format"], record["holdout"])
    if ds.backgrounds is None or ds.masks is None:
        raise SystemExit(f"error: {record['path']}: no ground-truth backgrounds or masks to find the effects from")
    effects = effect_masks(ds.images, ds.backgrounds, ds.masks)
    data = effect_copy(record["path"], effects, ds.names, os.path.join(out, "data"))
    strategy = FitConfig().bg_strategy
    refit([run, strategy, os.path.join(out, "without")])
    refit([run, strategy, os.path.join(out, "with"), data])
    dil = score_dilation(ds.size)
    tests = [v for v in ds.test if np.isfinite(ds.backgrounds[v]).all()]
    baselines = {}
    for name in ("telea", "ns"):
        scores = []
        for v in tests:
            region = dilate(ds.masks[v], dil)
            filled = inpainter(name)(np.clip(ds.images[v], 0, 1), region | effects[v])
            scores.append(psnr(filled, ds.backgrounds[v], region))
        baselines[name] = float(np.mean(scores)) if scores else None
    rows = {}
    for key in ("without", "with"):
        with open(os.path.join(out, key, "metrics.json")) as f:
            rows[key] = json.load(f)
    share = [effects[v].sum() / max(ds.masks[v].sum(), 1) for v in ds.train]
    write_json(os.path.join(out, "metrics.json"), {
        "strategy": strategy, "without": rows["without"], "with": rows["with"], "effects_2d": baselines,
        "effect_share": float(np.mean(share))})


if __name__ == "__main__":
    main()
