"""#46: held-out views of a family scene cropped about the mask, side by side: the photo, the true background, OpenCV
Telea on the scored (dilated) mask, the run's full field and its background (renders of `scripts/render.py RUN/scene.xml
--cameras DATA --split test --out RENDERS`). Writes OUT (a PNG; refuses an existing file).

    python hole_crops.py DATA RENDERS VIEWS OUT.png
"""
import os
import sys

import numpy as np
from PIL import Image

from mi_voldis.data import load_dataset
from mi_voldis.inpaint2d import inpainter
from mi_voldis.metrics import dilate, score_dilation

if len(sys.argv) != 5:
    raise SystemExit("usage: python hole_crops.py DATA RENDERS VIEWS OUT.png")
data, renders, out = sys.argv[1], sys.argv[2], sys.argv[4]
if os.path.lexists(out):
    raise SystemExit(f"error: {out} exists; give another OUT")
ds = load_dataset(data)
dil = score_dilation(ds.size)
rows = []
for v in [int(x) for x in sys.argv[3].split(",")]:
    hole = dilate(ds.masks[v], dil)
    ys, xs = np.nonzero(hole)
    y0, y1, x0, x1 = max(ys.min() - 8, 0), ys.max() + 8, max(xs.min() - 8, 0), xs.max() + 8
    tiles = [ds.images[v], ds.backgrounds[v], inpainter("telea")(ds.images[v], hole)]
    tiles += [np.asarray(Image.open(os.path.join(renders, f"view_{v:03d}_{k}.png")).convert("RGB")) / 255.0
              for k in ("full", "bg")]
    row = np.concatenate([np.clip(t[y0:y1, x0:x1, :3], 0, 1) for t in tiles], 1)
    size = (1000, round(1000 * row.shape[0] / row.shape[1]))
    rows.append(np.asarray(Image.fromarray((row * 255).astype(np.uint8)).resize(size)))
image = Image.fromarray(np.concatenate(rows, 0))
image.save(out)
