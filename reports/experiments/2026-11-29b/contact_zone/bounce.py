"""family17's floor just below the object's mask: the photo against the truth (rendered without the object) and
the default background's preview, mean 8-bit RGB of each row across the mask's columns.

    python reports/experiments/2026-11-29b/contact_zone/bounce.py DATASET REFIT [VIEW]
REFIT: a `python -m mi_voldis.bench.strategies` output folder (its viewNNN_bg.png)."""
import glob
import sys

import imageio.v3 as iio
import numpy as np

data, refit = sys.argv[1:3]
v = int(sys.argv[3]) if len(sys.argv) > 3 else 8
photo = iio.imread(sorted(glob.glob(f"{data}/images/*"))[v])[..., :3].astype(float)
truth = iio.imread(sorted(glob.glob(f"{data}/backgrounds/*"))[v])[..., :3].astype(float)
ours = iio.imread(f"{refit}/view{v:03d}_bg.png")[..., :3].astype(float)
mask = iio.imread(sorted(glob.glob(f"{data}/masks/*"))[v])
mask = mask.reshape(mask.shape[0], mask.shape[1], -1)[..., 0] > 0
ys, xs = np.nonzero(mask)
cols = slice(xs.min(), xs.max())
print(f"view {v}: mask rows {ys.min()}-{ys.max()}, columns {xs.min()}-{xs.max()}")
for y in range(ys.max() - 3, ys.max() + 8):
    print(f"row {y} ({'in' if mask[y].any() else 'below'} the mask): photo {photo[y, cols].mean(0).round()}, "
          f"truth {truth[y, cols].mean(0).round()}, background {ours[y, cols].mean(0).round()}")
