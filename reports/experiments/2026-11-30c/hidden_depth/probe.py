"""#46 item 3: the depth hole_carve gives the surface the statue hides, against the depth beside the mask.
For masked training views of RUN: the full field's median depth, the filled depth (`hidden_depth`), and the
depths left and right of the mask on the same rows. Writes depth sheets (log depth) to OUT.

    python probe.py RUN OUT [VIEWS]
"""
# ruff: noqa: E402
import os
import sys

import numpy as np

import mi_voldis  # noqa: F401

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.fit.lift import training_depths
from mi_voldis.fit.visibility import hidden_depth
from mi_voldis.io.images import write_png
from mi_voldis.masks3d import dilate

run, out = sys.argv[1], sys.argv[2]
os.makedirs(out, exist_ok=True)
cfg, ds, state, inputs = load_run(run)
depth = training_depths(inputs, state, median=True)
masked = set(int(v) for v in ds.masked_train)
views = [v for v in depth if v in masked]
if len(sys.argv) > 3:
    views = [int(v) for v in sys.argv[3].split(",")]
grow = int(np.ceil(0.01 * np.hypot(*ds.size)))
for v in views:
    d = depth[v]
    m = np.asarray(ds.masks[v], bool)
    hole = dilate(m, grow)
    filled = hidden_depth(ds.cameras[v], d, m, hole)
    if filled is None:
        continue
    # per row: the nearest hit pixel beyond the grown mask on the left and the right
    side = []
    for y in np.nonzero(hole.any(1))[0]:
        xs = np.nonzero(hole[y])[0]
        lo, hi = xs.min(), xs.max()
        left = d[y, max(lo - 8, 0):lo]
        right = d[y, hi + 1:hi + 9]
        vals = np.concatenate([left[np.isfinite(left)], right[np.isfinite(right)]])
        if len(vals):
            side.append((y, np.median(vals), np.median(filled[y, xs])))
    side = np.array(side)
    rows = np.linspace(0, len(side) - 1, 6).round().astype(int)
    print(f"view {v}: object depth (median in mask) {np.nanmedian(d[m]):.1f}; filled in hole median "
          f"{np.median(filled[hole]):.1f}; beside the mask, by row (row, sides, filled):",
          "; ".join(f"{int(side[k,0])}: {side[k,1]:.0f} / {side[k,2]:.0f}" for k in rows))
    lo, hi = np.log(np.nanpercentile(d, 2)), np.log(np.nanpercentile(d, 98))

    def img(x):
        g = np.clip((np.log(np.where(np.isfinite(x), x, np.exp(hi))) - lo) / (hi - lo), 0, 1)
        return np.repeat(g[..., None], 3, -1)
    a, b = img(d), img(filled)
    edge = hole & ~dilate(~hole, 1)
    b[edge ^ dilate(edge, 1)] = [1, 0, 0]
    photo = np.clip(ds.images[v][..., :3], 0, 1) ** (1 / 2.2)
    sheet = np.concatenate([photo, a, b], 1)
    write_png(os.path.join(out, f"view{v:03d}.png"), (sheet * 255).round().astype(np.uint8))
