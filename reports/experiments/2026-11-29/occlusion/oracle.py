"""#46: what the hole would score with parts of its error removed (an oracle, not a method): ours, the ring 1-3% made
perfect, the core's mean error removed, both; Telea from the photos and from the true backgrounds.
    python reports/experiments/2026-11-29/occlusion/oracle.py 10 11 14 ..."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-28", "prior_seen"))
from common import FITS, guided_row, image, mask

from mi_voldis.inpaint2d import opencv_inpaint
from mi_voldis.metrics import dilate


def psnr(mse):
    return -10 * np.log10(mse)


for s in sys.argv[1:]:
    sc = f"family{s}"
    rows = []
    for v in (0, 8, 16):
        truth = image(f"{FITS}/data/{sc}/backgrounds/view_{v:03d}.png")
        photo = image(f"{FITS}/data/{sc}/images/view_{v:03d}.png")
        ours = image(f"{guided_row(sc)}/view{v:03d}_bg.png")
        m = mask(sc, v)
        d = np.hypot(*m.shape)
        # the hole: the mask grown by 3% of the diagonal; its core: grown by 1%; the ring (band) in between
        reg = dilate(m, int(np.ceil(0.03 * d)))
        inner = dilate(m, int(np.ceil(0.01 * d)))
        band = reg & ~inner
        e = ours - truth
        mse = (e[reg] ** 2).mean()
        # ring made perfect
        e2 = e.copy()
        e2[band] = 0
        mse_ringok = (e2[reg] ** 2).mean()
        # core's mean error removed
        e3 = e.copy()
        e3[inner] -= e[inner].mean(0)
        mse_nobias = (e3[reg] ** 2).mean()
        # both
        e4 = e2.copy()
        e4[inner] -= e[inner].mean(0)
        mse_both = (e4[reg] ** 2).mean()
        # Telea inpainting of the hole, from the photo and from the true background
        tp = opencv_inpaint(photo, reg)
        tt = opencv_inpaint(truth, reg)
        rows.append([
            psnr(mse),
            psnr(mse_ringok),
            psnr(mse_nobias),
            psnr(mse_both),
            psnr(((tp - truth)[reg] ** 2).mean()),
            psnr(((tt - truth)[reg] ** 2).mean()),
        ])
    r = np.array(rows)
    print(sc, "ours/ring-perfect/core-unbiased/both | telea photo/telea truth-sources:", np.round(r.mean(0), 2))
