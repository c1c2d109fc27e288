"""#46: the dark patch left where garden's vase stood, against the photo. Writes OUT.png: view VIEW's photo and its
background layer (`bench.strategies`' preview), cropped to the plate, the mask's edge in magenta, twice the size.

    python reflection_crop.py RUN DATA STRATEGIES_OUT VIEW OUT.png
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

run, data, strategies_out, view, out = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5]
if os.path.exists(out):
    raise SystemExit(f"error: {out}: already there")
_, ds, _, _ = load_run(run, data)
photo = display_to_uint8(np.clip(ds.images[view], 0, 1))[..., :3]
background = iio.imread(os.path.join(strategies_out, f"view{view:03d}_bg.png"))[..., :3]
edge = dilate(ds.masks[view], 1) & ~ds.masks[view]
panels = []
for image in (photo, background):
    image = image.copy()
    image[edge] = (255, 0, 255)
    panels.append(image[220:380, 160:330])
crop = np.concatenate(panels, 1)
iio.imwrite(out, np.repeat(np.repeat(crop, 2, 0), 2, 1))
