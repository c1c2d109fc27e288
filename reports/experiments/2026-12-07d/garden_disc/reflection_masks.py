"""#46: effect masks for the pot's reflection and contact shadow on garden's metal plate, in a few training views,
by a rule standing in for a user's brush: outside the object's mask, within 40 pixels of it, below the mask's
lowest quarter (the plate in front of the pot), and darker than the 15th percentile of that band's luminance.
Writes OUT/<image stem>.png (white = effect) for `make_masks.py --effects --from-views`, and OUT/sheet.png (cyan:
the effect, magenta: the mask's edge). Refuses an OUT that exists.

    python reflection_masks.py RUN DATA OUT VIEWS
"""
# ruff: noqa: E402
import os
import sys

import imageio.v3 as iio
import numpy as np

import mi_voldis  # noqa: F401

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.io.images import display_to_uint8
from mi_voldis.metrics import dilate

run, data, out, views = sys.argv[1], sys.argv[2], sys.argv[3], [int(v) for v in sys.argv[4].split(",")]
if os.path.exists(out):
    raise SystemExit(f"error: {out}: already there")
_, ds, _, _ = load_run(run, data)
os.makedirs(out)
rows = []
for v in views:
    img = display_to_uint8(np.clip(ds.images[v], 0, 1))[..., :3]
    mask = ds.masks[v]
    ys = np.nonzero(mask)[0]
    band = dilate(mask, 40) & ~mask
    band[:int(np.percentile(ys, 75))] = False
    lum = img.mean(-1)
    effect = band & (lum < np.percentile(lum[band], 15))
    iio.imwrite(os.path.join(out, os.path.splitext(os.path.basename(ds.names[v]))[0] + ".png"),
                (effect * 255).astype(np.uint8))
    shown = img.copy()
    shown[dilate(mask, 1) & ~mask] = (255, 0, 255)
    shown[effect] = (0, 255, 255)
    rows.append(np.concatenate([img, shown], 1)[::2, ::2])
    print(f"view {v} ({ds.names[v]}): {int(effect.sum())} effect pixels")
iio.imwrite(os.path.join(out, "sheet.png"), np.concatenate(rows, 0))
