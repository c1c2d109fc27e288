"""#46 item 3: is garden's hole hazier than the surface it shows? The metal disc where the vase stood holds the
hole's haze (2026-11-30c heat maps); this compares, per held-out view, the background's haze on the hole's disc
pixels with the full field's own haze on the disc pixels that views see beside the vase (outside the scored
hole, within 3% of the diagonal of it), and the table's wood on both sides of the hole's edge.

Refits RUN's background as `bench.strategies RUN guided OUT DATA --refit` does, keeping the state in OUT/state.npz
(a second call reuses it; a folder OUT that holds anything else is refused). Pixels are told apart by the colour
of the layer that shows them: grey-blue metal (blue at least red) against brown wood (red above blue by 0.03 and
above green) in the rendered layer; the rest (grass, bushes, paving) is left out.

    python disc_haze.py RUN OUT DATA VIEWS
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from kept_background import kept_background  # noqa: E402

from mi_voldis.metrics import dilate, score_dilation  # noqa: E402
from mi_voldis.render.surface import front_weight  # noqa: E402
from mi_voldis.render.views import render_camera  # noqa: E402

run, out, data, views = sys.argv[1], sys.argv[2], sys.argv[3], [int(v) for v in sys.argv[4].split(",")]
if os.path.exists(out) and set(os.listdir(out)) - {"state.npz"}:
    raise SystemExit(f"error: {out}: holds files this probe did not write")
os.makedirs(out, exist_ok=True)
ds, inputs, state, integrator = kept_background(run, out, data)
dil = score_dilation(ds.size)
ring_px = int(np.ceil(0.03 * np.hypot(*ds.size)))


def kinds(rgb):
    """Metal (grey-blue) and wood (brown) pixels of a display-space image."""
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return b >= r, (r > b + 0.03) & (r > g)


def mean(values, where):
    return float(values[where].mean()) if where.any() else float("nan")


sums = {}
print("view  bg hole: metal (n) wood (n) | full beside: metal (n) wood (n) | bg beside: metal wood | bg outside")
for v in views:
    cam = ds.cameras[v]
    hole = dilate(ds.masks[v], dil)
    ring = dilate(hole, ring_px) & ~hole
    layers = render_camera(integrator, cam, ("bg", "full"))
    shown = {k: np.clip(ds.as_photographed(layers[k]), 0, 1) for k in ("bg", "full")}
    bg_front, bg_hit = front_weight(integrator, cam, layer="bg")
    full_front, full_hit = front_weight(integrator, cam, layer="full")
    metal_bg, wood_bg = kinds(shown["bg"])
    metal_full, wood_full = kinds(shown["full"])
    row = {
        "bg hole metal": (bg_front, hole & bg_hit & metal_bg), "bg hole wood": (bg_front, hole & bg_hit & wood_bg),
        "full ring metal": (full_front, ring & full_hit & metal_full),
        "full ring wood": (full_front, ring & full_hit & wood_full),
        "bg ring metal": (bg_front, ring & bg_hit & metal_bg), "bg ring wood": (bg_front, ring & bg_hit & wood_bg),
        "bg outside": (bg_front, ~hole & bg_hit), "bg hole": (bg_front, hole & bg_hit)}
    for k, (f, w) in row.items():
        s = sums.setdefault(k, [0.0, 0])
        s[0] += float(f[w].sum())
        s[1] += int(w.sum())
    m = {k: (mean(f, w), int(w.sum())) for k, (f, w) in row.items()}
    print(f"{v:4d}  {m['bg hole metal'][0]:.3f} ({m['bg hole metal'][1]}) {m['bg hole wood'][0]:.3f} "
          f"({m['bg hole wood'][1]}) | {m['full ring metal'][0]:.3f} ({m['full ring metal'][1]}) "
          f"{m['full ring wood'][0]:.3f} ({m['full ring wood'][1]}) | {m['bg ring metal'][0]:.3f} "
          f"{m['bg ring wood'][0]:.3f} | {m['bg outside'][0]:.3f}")
print("all views, pixel-weighted:")
for k, (s, n) in sums.items():
    print(f"  {k}: {s / max(n, 1):.3f} over {n} pixels")
