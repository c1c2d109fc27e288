"""#46 item 3: in which region of the background's start garden's hole haze lies. For held-out VIEWS, the rays
through the scored hole (the mask dilated as the bench scores it) are marched through the background kept by
`disc_haze.py` (OUT/state.npz); each sample's weight in front of 0.9 of the ray's median depth (the haze figure's
weight) is put in the nearest stored vertex's region (mi_voldis.fit.background.background_regions): outside the
visual hull, a kept hull vertex (some view sees it unmasked), a refilled one, or the object's own. Printed per view
and summed: the mean front weight per hole ray in each region, for the hole's metal and wood pixels (told apart by
the background layer's colour as in `disc_haze.py`) and for all of it.

    python front_regions.py RUN OUT DATA VIEWS
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from kept_background import REGIONS, kept_background, region_lookup, region_weights  # noqa: E402

from mi_voldis.cameras import pixel_rays  # noqa: E402
from mi_voldis.metrics import dilate, score_dilation  # noqa: E402
from mi_voldis.render.surface import median_points  # noqa: E402
from mi_voldis.render.views import render_camera  # noqa: E402

run, out, data, views = sys.argv[1], sys.argv[2], sys.argv[3], [int(v) for v in sys.argv[4].split(",")]
ds, inputs, state, integrator = kept_background(run, out, data)
lookup = region_lookup(inputs, state)
names = REGIONS
dil = score_dilation(ds.size)
totals = {k: np.zeros(4) for k in ("metal", "wood", "all")}
counts = {k: 0 for k in totals}
for v in views:
    cam = ds.cameras[v]
    hole = dilate(ds.masks[v], dil)
    rgb = np.clip(ds.as_photographed(render_camera(integrator, cam, ("bg",))["bg"]), 0, 1)
    py, px = np.nonzero(hole)
    o, d = pixel_rays(cam, px + 0.5, py + 0.5)
    med, hit = median_points(integrator, o, d, layer="bg")
    reach = np.where(hit, 0.9 * np.linalg.norm(med - o, axis=1), 0.0)
    share = region_weights(integrator, lookup, o, d,
                           lambda world, active: active & (np.linalg.norm(world - o, axis=1) < reach))
    c = rgb[py, px]
    kinds = {"metal": (c[:, 2] >= c[:, 0]) & hit, "wood": (c[:, 0] > c[:, 2] + 0.03) & (c[:, 0] > c[:, 1]) & hit,
             "all": hit}
    line = []
    for k, sel in kinds.items():
        totals[k] += share[sel].sum(0)
        counts[k] += int(sel.sum())
        line.append(f"{k} ({sel.sum()}): " + " ".join(f"{x:.3f}" for x in share[sel].mean(0)) if sel.any() else k)
    print(f"view {v}: " + " | ".join(line), flush=True)
print("regions: " + ", ".join(names))
for k in totals:
    per_ray = totals[k] / max(counts[k], 1)
    print(f"all views, {k} ({counts[k]} rays): " + ", ".join(f"{n} {x:.3f}" for n, x in zip(names, per_ray))
          + f"; sum {per_ray.sum():.3f}")
