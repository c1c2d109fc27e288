"""#46: what the dark patch where garden's vase stood is. For three windows of held-out view 8 (the patch, 205-255 x
285-315; the plate above it, inside the mask; the wood below it), each layer's median depth and median point, the
region of the background's start (outside the visual hull / kept hull / refilled / the object's) that holds the
median points, and the share of the window inside view 8's object mask. The background is the one `disc_haze.py`
kept in OUT/state.npz.

    python blob_probe.py RUN OUT DATA
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from kept_background import kept_background, region_lookup  # noqa: E402

from mi_voldis.cameras import pixel_rays  # noqa: E402
from mi_voldis.render.surface import median_points  # noqa: E402

run, out, data = sys.argv[1], sys.argv[2], sys.argv[3]
ds, inputs, state, integrator = kept_background(run, out, data)
lookup = region_lookup(inputs, state)
cam = ds.cameras[8]
windows = {"blob": (205, 255, 285, 315), "plate above it": (205, 255, 245, 265), "wood below": (205, 255, 345, 365)}
for name, (x0, x1, y0, y1) in windows.items():
    py, px = np.mgrid[y0:y1, x0:x1]
    px, py = px.ravel(), py.ravel()
    o, d = pixel_rays(cam, px + 0.5, py + 0.5)
    for layer in ("bg", "full"):
        med, hit = median_points(integrator, o, d, layer=layer)
        t = np.linalg.norm(med - o, axis=1)
        c = np.bincount(lookup(np.array(inputs.space.from_world_np(med[hit]))), minlength=4)
        lo, hi = np.percentile(t[hit], 10), np.percentile(t[hit], 90)
        print(f"{name} {layer}: median depth {np.median(t[hit]):.3f} (10-90%: {lo:.3f}-{hi:.3f}); "
              f"median point world {np.round(np.median(med[hit], 0), 3)}; regions out/kept/refilled/object "
              f"{c.tolist()}; mask share {ds.masks[8][py, px].mean():.2f}")
