"""The shadow search on a fitted run, against the ground truth where there is one.

    [MASK_EDGE_PX=N] python reports/experiments/2026-11-25b/shadow_check.py RUN [X,Y,Z ...]

RUN: a fit kept with --keep-checkpoints. Prints the light the default search finds (its record), the
IoU / precision / recall of its effect masks against the ground truth's (photo against true background
outside the object's mask, every masked training view), the spread of the object's surface points
(distance from their median point, before the visual hull's filter), and for each light X,Y,Z given
(e.g. the scene's true point light) its score, shading and masks' IoU. Writes RUN_shadow.png beside
RUN: five masked training views, the found shadow in red, the true effect masks in blue. MASK_EDGE_PX:
the pixels beyond the masks the search leaves out (``mi_voldis.fit.shadow.MASK_EDGE_PX``; before
f6aeb3f it was the hull's dilation, 6 pixels at 160 x 120, 19 on the statue).
"""
import json
import os
import sys

import numpy as np

from mi_voldis.bench.effects import effect_masks
from mi_voldis.bench.strategies import refit_config
from mi_voldis.data import load_dataset
from mi_voldis.fit import shadow as S
from mi_voldis.fit.fields import FitInputs
from mi_voldis.fit.hull import visual_hull
from mi_voldis.fit.lift import training_depths
from mi_voldis.fit.state import FitState
from mi_voldis.io.images import display_to_uint8, write_png
from mi_voldis.optim.adam import Adam


def overlap(est, gt):
    i, u = (est & gt).sum(), (est | gt).sum()
    return f"IoU {i / max(u, 1):.3f} precision {i / max(est.sum(), 1):.2f} recall {i / max(gt.sum(), 1):.2f}"


def main(run, *lights):
    S.MASK_EDGE_PX = int(os.environ.get("MASK_EDGE_PX", S.MASK_EDGE_PX))  # the search's band beyond the masks
    cfg = refit_config(run, "guided")
    with open(os.path.join(run, "config.json")) as f:
        rec = json.load(f)["dataset"]
    ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
    state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, cfg.adam_beta1, cfg.adam_beta2))
    inputs = FitInputs.of(ds, cfg, os.path.join(run, "unused.npz"), False)
    found, record = S.find_shadow(inputs, state)
    print("search:", record)
    masked = list(ds.masked_train)
    gt = effect_masks(ds.images, ds.backgrounds, ds.masks) if ds.backgrounds is not None else None
    found = np.zeros(ds.masks.shape, bool) if found is None else found
    if gt is not None:
        print("found against the true effect masks:", overlap(found[masked], gt[masked]))
    depth = training_depths(inputs, state, count=len(ds.train), median=True)
    masked = [v for v in masked if v in depth]
    cams, masks, depths = ([seq[v] for v in masked] for seq in (ds.cameras, ds.masks, depth))
    grow = int(np.ceil(cfg.hull_dilation * np.hypot(*ds.size)))
    surface = S.ObjectSurface.of(cams, [ds.images[v] for v in masked], masks, depths)
    d = np.linalg.norm(surface.points - np.median(surface.points, 0), axis=1)
    print("object points' distance from their median point, quantiles 0.5 / 0.9 / 0.99 / max:",
          np.round(np.quantile(d, [0.5, 0.9, 0.99, 1.0]), 3).tolist())
    surface = surface.inside(visual_hull(surface.points, cams, masks, grow, cfg.hull_min_views, depths))
    pick = np.unique(np.linspace(0, len(masked) - 1, min(12, len(masked))).round().astype(int))
    views = S.ShadowViews.of([cams[k] for k in pick], [ds.images[masked[k]] for k in pick], [masks[k] for k in pick],
                             [depths[k] for k in pick], S.MASK_EDGE_PX)
    obj, spacing = surface.points, surface.spacing
    if len(obj) > 20000:  # as find_light subsamples
        spacing *= np.sqrt(len(obj) / 20000)
        obj = obj[np.random.default_rng(cfg.seed).choice(len(obj), 20000, replace=False)]
    radius, centre = spacing / np.sqrt(2.0), obj.mean(0)
    for text in lights:
        p = np.array([float(x) for x in text.split(",")])
        t, contrast, agree = views.score(S.ShadowMap(p, centre, obj, radius), cfg.shadow_contrast)
        line = f"light {p.tolist()}: t {t:.2f}, edge contrast {contrast:.3f}, views agreeing {agree:.2f}, " \
               f"shading {surface.shading(p):.3f}"
        if gt is not None:
            light = S.ShadowLight(p, t, contrast, agree, surface.shading(p), True)
            est = S.shadow_masks(light, (obj, radius, centre), cams, masks, depths,
                                 int(np.ceil(S.GROW * np.hypot(*ds.size))))
            line += "; its masks " + overlap(est, gt[masked])
        print(line)
    rows = []
    for v in masked[:: max(1, len(masked) // 5)][:5]:
        img = display_to_uint8(np.clip(ds.images[v], 0, 1)).copy()
        if gt is not None:
            img[gt[v]] = (0.6 * img[gt[v]] + [0, 0, 100]).astype(np.uint8)
        img[found[v]] = (0.6 * img[found[v]] + [100, 0, 0]).astype(np.uint8)
        rows.append(img)
    write_png(run.rstrip("/") + "_shadow.png", np.concatenate(rows, 1))


if __name__ == "__main__":
    main(*sys.argv[1:])
