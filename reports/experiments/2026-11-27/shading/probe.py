"""The shadow search's terms at named lights: which measure of the object's shading tells a true light.

    python reports/experiments/2026-11-27/shading/probe.py [--lights FILE] RUN [RUN ...] > out.json

Per RUN (a fit kept with its checkpoints): the full field's median depths of the masked training views
(as mi_voldis.fit.shadow.find_shadow takes them), then at the true light (the dataset's scene.xml), the
light the fit recorded and the light today's search finds: the edge score (t, contrast, agreement,
receiver cosine), the measured shading, the predicted shading and their ratio, and the counts of the
object's points facing the light and facing away.
"""
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(HERE)))))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "shadow"))

import re  # noqa: E402

from search import kept_run  # noqa: E402
from search import true_light as rect_or_point  # noqa: E402

from mi_voldis.fit import shadow as sh  # noqa: E402
from mi_voldis.fit.hull import visual_hull  # noqa: E402
from mi_voldis.fit.lift import training_depths  # noqa: E402


def true_light(dataset):
    """The dataset's light: search.py's forms, or a point light given by x, y, z attributes."""
    found = rect_or_point(dataset)
    path = os.path.join(dataset, "scene", "scene.xml")
    if found is None and os.path.isfile(path):
        with open(path) as f:
            m = re.search(r'type="point"><point name="position" x="([^"]+)" y="([^"]+)" z="([^"]+)"', f.read())
        found = [float(v) for v in m.groups()] if m else None
    return found


def terms(p, surface, views, obj, radius, centre, min_contrast):
    p = np.asarray(p, float)
    t, c, agree, cos_r = views.score(sh.ShadowMap(p, centre, obj, radius), min_contrast)
    with np.errstate(invalid="ignore"):
        cos = np.sum((p - surface.points) * surface.normals, axis=1) / np.linalg.norm(p - surface.points, axis=1)
    shading = surface.shading(p)
    pred = surface.predicted_shading(p, c, cos_r)
    return {"light": p.tolist(), "t": t, "contrast": c, "agree": agree, "receiver_cos": cos_r,
            "shading": shading, "predicted": pred, "ratio": pred / shading if shading > 0 else None,
            "lit_points": int((cos > sh.FACING).sum()), "dark_points": int((cos < -sh.FACING).sum()),
            "points": len(cos),
            "elevation_deg": float(np.degrees(np.arcsin((p - centre)[1] / np.linalg.norm(p - centre))))}


def probe(run, extra=None):
    record, before, inputs, state = kept_run(run)
    ds, cfg = inputs.ds, inputs.cfg
    depth = training_depths(inputs, state, count=len(ds.train), median=True)
    masked = [v for v in ds.masked_train if v in depth]
    cams, masks, depths = ([seq[v] for v in masked] for seq in (ds.cameras, ds.masks, depth))
    grow = int(np.ceil(cfg.hull_dilation * np.hypot(*ds.size)))
    surface = sh.ObjectSurface.of(cams, [ds.images[v] for v in masked], masks, depths)
    surface = surface.inside(visual_hull(surface.points, cams, masks, grow, cfg.hull_min_views, depths))
    pick = np.unique(np.linspace(0, len(masked) - 1, min(12, len(masked))).round().astype(int))
    views = sh.ShadowViews.of([cams[k] for k in pick], [ds.images[masked[k]] for k in pick], [masks[k] for k in pick],
                              [depths[k] for k in pick], sh.MASK_EDGE_PX)
    now, (obj, radius, centre) = sh.find_light(views, surface, cfg.shadow_contrast, seed=cfg.seed)
    out = {"run": run, "found_now": now.record()}
    for name, p in (("true", true_light(record["path"])), ("recorded", before and before["light"]),
                    ("now", now.position), ("given", extra)):
        if p is not None:
            out[name] = terms(p, surface, views, obj, radius, centre, cfg.shadow_contrast)
    return out


if __name__ == "__main__":
    args = sys.argv[1:]
    given = {}
    if args[:1] == ["--lights"]:  # a JSON file {run folder name: {"light_in_report": {"light": [x, y, z]}}}
        with open(args[1]) as f:
            given = {k: v["light_in_report"]["light"] for k, v in json.load(f).items() if "light_in_report" in v}
        args = args[2:]
    print(json.dumps([probe(r, given.get(os.path.basename(r.rstrip("/")))) for r in args], indent=1, default=float))
