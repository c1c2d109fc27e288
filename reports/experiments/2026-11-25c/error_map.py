"""Where a removal's error lies: per held-out view, the in-mask PSNR of a refit's background and the
share of its squared error inside the object's mask and in the ring the dilation adds (the ring holds
a shadow cast straight down); writes a sheet (photo, truth, background, error x20 in the dilated mask).

    python reports/experiments/2026-11-25c/error_map.py DATA REFIT OUT.png

DATA: a ground-truth dataset (make_dataset.py); REFIT: a ``python -m mi_voldis.bench.strategies`` output
(its viewNNN_bg.png previews of the held-out views).
"""
import glob
import os
import re
import sys

import imageio.v3 as iio
import numpy as np

from mi_voldis.io.images import write_png
from mi_voldis.metrics import dilate

DILATION = 0.03  # the benchmark's in-mask region: the masks grown by this share of the diagonal


def read_image(path):
    return iio.imread(path).astype(np.float32) / 255.0


def main(data, refit, out):
    rows = []
    for path in sorted(glob.glob(os.path.join(refit, "view*_bg.png"))):
        v = int(re.search(r"view(\d+)_bg", path).group(1))
        photo, truth, bg = (read_image(p)[..., :3] for p in (
            f"{data}/images/view_{v:03d}.png", f"{data}/backgrounds/view_{v:03d}.png", path))
        mask = read_image(f"{data}/masks/view_{v:03d}.png")
        mask = (mask if mask.ndim == 2 else mask[..., 0]) > 0.5
        region = dilate(mask, int(np.ceil(DILATION * np.hypot(*mask.shape))))
        err = ((bg - truth) ** 2).mean(-1)
        total = err[region].sum()
        print(f"view {v}: in-mask PSNR {-10 * np.log10(err[region].mean()):.2f} dB; squared error in the mask "
              f"{err[mask].sum() / total:.2f}, in the ring {err[region & ~mask].sum() / total:.2f}")
        heat = np.repeat((np.clip(err * 20, 0, 1) * region)[..., None], 3, -1)
        rows.append(np.concatenate([photo, truth, bg, heat], 1))
    write_png(out, (np.clip(np.concatenate(rows, 0), 0, 1) * 255).astype(np.uint8))


if __name__ == "__main__":
    main(*sys.argv[1:])
