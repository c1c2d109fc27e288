"""#46: where a ray of a held-out view enters family18's object, from its scene file's cube (analytic), and where
it meets the floor (y = 0).

    python reports/experiments/2026-11-29c/coverage/box_entry.py RUN VIEW X,Y ...   # RUN: family18's fit
"""
# ruff: noqa: E702  (a probe kept as it ran)
import json
import os
import sys

import numpy as np

import mi_voldis  # noqa: F401  (sets the variant)
from mi_voldis.cameras import pixel_rays
from mi_voldis.data import load_dataset

run, v = sys.argv[1], int(sys.argv[2])
pix = [tuple(int(x) for x in s.split(",")) for s in sys.argv[3:]]
rec = json.load(open(os.path.join(run, "config.json")))["dataset"]
ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
o, d = pixel_rays(ds.cameras[v], np.array([p[0] for p in pix]) + 0.5, np.array([p[1] for p in pix]) + 0.5)
s = np.array([0.171004, 0.0985754, 0.162851]); a = np.radians(21.31); T = np.array([0, 0.0985754, 0])
R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
for k in range(len(o)):
    lo = R.T @ (o[k] - T) / s; ld = R.T @ d[k] / s
    t1, t2 = (-1 - lo) / ld, (1 - lo) / ld
    tn, tf = np.minimum(t1, t2).max(), np.maximum(t1, t2).min()
    tfloor = -o[k][1] / d[k][1]
    print(pix[k], "box enter", round(tn, 3) if tn < tf else None, "floor t", round(tfloor, 3))
