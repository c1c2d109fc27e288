"""A refitted background's held-out views beside the photo, the truth and FSR's fill (the `guided` prior's 2D
inpainter), cropped around the object of family17 and enlarged 4x.

    python reports/experiments/2026-11-29b/contact_zone/views.py DATASET REFIT OUT.png
REFIT: a `python -m mi_voldis.bench.strategies` output folder (its viewNNN_bg.png)."""
import os
import sys

import cv2
import imageio.v3 as iio
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
from mi_voldis.data import load_dataset  # noqa: E402
from mi_voldis.inpaint2d import inpainter  # noqa: E402
from mi_voldis.metrics import dilate, psnr, score_dilation  # noqa: E402

data, refit, out = sys.argv[1:4]
if os.path.exists(out):  # a picture of someone else's is not replaced
    sys.exit(f"error: {out}: already exists (give a new file name)")
ds = load_dataset(data, "transforms", 8)
dil = score_dilation(ds.size)
rows = []
for v in ds.test:
    region = dilate(ds.masks[v], dil)
    fsr = inpainter("fsr")(ds.images[v], region)
    ours = iio.imread(f"{refit}/view{v:03d}_bg.png")[..., :3] / 255.0
    print(f"view {v}: in the mask FSR {psnr(fsr, ds.backgrounds[v], region):.2f} dB, "
          f"background (8-bit preview) {psnr(ours, ds.backgrounds[v], region):.2f} dB")

    def crop(a):
        return (np.clip(a[20:72, 36:84], 0, 1) * 255).astype(np.uint8)
    rows.append(np.concatenate([crop(ds.images[v]), crop(ds.backgrounds[v]), crop(ours), crop(fsr)], 1))
iio.imwrite(out, cv2.resize(np.concatenate(rows, 0), None, fx=4, fy=4, interpolation=cv2.INTER_NEAREST))
