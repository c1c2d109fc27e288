"""family22's in-mask error split: the background (REMOVAL/family22/guided/viewNNN_bg.png) against the truth in
the scored mask, in its ring (the mask dilated as scored, less the object's own mask), on the object's pixels and
outside; the full field's previews against the photo; the photo against the truth in the ring (the object's light on
its surroundings: what a background fitted to the photos keeps there).

    python ring.py DATA REMOVAL RUN
"""
import os
import sys

import imageio.v3 as iio
import numpy as np

import mi_voldis  # noqa: F401
from mi_voldis.data import load_dataset
from mi_voldis.io.images import display_to_uint8
from mi_voldis.metrics import dilate, psnr, score_dilation

data, removal, run = sys.argv[1:4]
ds = load_dataset(data, "transforms", 8)
dil = score_dilation(ds.size)


def shown(x):
    return display_to_uint8(np.clip(x, 0, 1))[..., :3] / 255.0


for v in ds.test:
    bg = iio.imread(os.path.join(removal, "family22", "guided", f"view{v:03d}_bg.png"))[..., :3] / 255.0
    gt, photo = shown(ds.backgrounds[v]), shown(ds.images[v])
    m = dilate(ds.masks[v], dil)
    ring, obj = m & ~ds.masks[v], ds.masks[v]
    line = (f"view {v}: background against the truth: mask {psnr(bg, gt, m):.2f}, ring {psnr(bg, gt, ring):.2f}, "
            f"object {psnr(bg, gt, obj):.2f}, outside {psnr(bg, gt, ~m):.2f} dB; photo against the truth in the "
            f"ring {psnr(photo, gt, ring):.2f}")
    preview = os.path.join(run, "previews", f"view{v:03d}_full.png")
    if os.path.isfile(preview):
        full = iio.imread(preview)[..., :3] / 255.0
        line += (f"; full field against the photo: ring {psnr(full, photo, ring):.2f}, "
                 f"outside {psnr(full, photo, ~m):.2f}")
    print(line)
