"""Is a found shadow physically consistent with the object's own shading?

    python reports/experiments/2026-11-27/shadow/diagnose.py RUN [RUN ...] > out.json

For each fitted RUN (a folder with scene.xml and metrics.json whose bg_prior records a shadow light), the
light the fit found is taken and checked against a two-term model of the lighting, radiance = albedo
(ambient + direct cos), with the shadow removing the direct term:

- on the receivers, the shadow's edge contrast c (log) gives the direct-to-ambient ratio
  k = (exp(c) - 1) / cos_r, where cos_r is the median cosine between the receivers' normals (from the
  full field's median depth maps) and the direction to the light;
- the object's points facing the light (cos > FACING) should then be brighter than its points facing
  away by log(1 + k cos) on average (same albedo on both sides, on average over the object).

The ratio of that predicted shading to the measured one (mi_voldis.fit.shadow.ObjectSurface.shading) is
what this prints per run, with cos_r and k: a grazing light that darkens the ground by c must be a strong
one, which would light the object's sides far more than the photos show.
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))))))

from mi_voldis import load_run  # noqa: E402
from mi_voldis.fit.shadow import FACING, ObjectSurface, ShadowMap, surface_points  # noqa: E402
from mi_voldis.render.surface import median_depth  # noqa: E402

VIEWS = 8


def diagnose(path):
    run = load_run(path)
    with open(os.path.join(path, "metrics.json")) as f:
        shadow = (json.load(f).get("bg_prior") or {}).get("shadow")
    if not shadow:
        return {"run": path, "shadow": None}
    ds = run.dataset
    integrator = run.integrator()
    masked = list(ds.masked_train)
    pick = [masked[k] for k in np.unique(np.linspace(0, len(masked) - 1, min(VIEWS, len(masked))).round().astype(int))]
    depths = {}
    for v in pick:
        depth, hit = median_depth(integrator, ds.cameras[v])
        depths[v] = np.where(hit, depth, np.nan)
    cams, masks = [ds.cameras[v] for v in pick], [ds.masks[v] for v in pick]
    surface = ObjectSurface.of(cams, [ds.images[v] for v in pick], masks, [depths[v] for v in pick])
    light = np.array(shadow["light"])
    centre = surface.points.mean(0)
    smap = ShadowMap(light, centre, surface.points[:: max(1, len(surface.points) // 20000)],
                     surface.spacing * np.sqrt(max(1, len(surface.points) // 20000)) / np.sqrt(2))
    cos_r = []
    for cam, mask, v in zip(cams, masks, pick):
        h, w = mask.shape
        ys, xs = np.mgrid[0:h:2, 0:w:2]
        pts, nrm = surface_points(cam, depths[v], xs, ys)
        ok = np.isfinite(pts).all(1) & np.isfinite(nrm).all(1) & ~mask[ys, xs].reshape(-1)
        s = np.zeros(len(pts), bool)
        s[ok] = smap.shadowed(pts[ok])
        to_light = light - pts[s]
        cos_r.append(np.sum(nrm[s] * to_light, 1) / np.linalg.norm(to_light, axis=1))
    cos_r = np.concatenate(cos_r) if cos_r else np.zeros(0)
    receiver = float(np.median(cos_r)) if len(cos_r) else float("nan")
    k = (np.exp(shadow["contrast"]) - 1.0) / max(receiver, 1e-3)
    with np.errstate(invalid="ignore"):
        to_light = light - surface.points
        cos_o = np.sum(to_light * surface.normals, 1) / np.linalg.norm(to_light, axis=1)
    lit = cos_o > FACING
    predicted = float(np.mean(np.log1p(k * cos_o[lit]))) if lit.any() else float("nan")
    measured = surface.shading(light)
    return {"run": path, "shadow": shadow, "shadowed_receivers": int(len(cos_r)),
            "receiver_cos_median": receiver, "receiver_facing_away": float(np.mean(cos_r < 0)) if len(cos_r) else None,
            "direct_to_ambient": float(k), "predicted_shading": predicted, "measured_shading": float(measured),
            "ratio": predicted / measured if measured > 0 else None}


if __name__ == "__main__":
    print(json.dumps([diagnose(p) for p in sys.argv[1:]], indent=1, default=float))
