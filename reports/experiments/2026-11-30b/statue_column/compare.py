"""Statue background refits side by side: each OUT folder's figures (haze in the hole / outside, residue,
consistency, coverage IoU) and a sheet of one held-out view's backgrounds (columns in the order given).

    python statue_column_cmp.py SHEET.png VIEW OUT [OUT ...]
"""
import json
import os
import sys

import imageio.v3 as iio
import numpy as np

sheet, view, outs = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
imgs = []
for out in outs:
    with open(os.path.join(out, "metrics.json")) as f:
        m = json.load(f)["methods"]["volume"]
    print(f"{os.path.basename(out)}: haze hole {m['bg_haze_mask']:.3f} / outside {m['bg_haze_outside']:.3f}, "
          f"residue vs Telea {m['residue_vs_telea']:.3f}, consistency {m['consistency_psnr']:.2f}, "
          f"coverage IoU {m['fg_coverage_iou']:.3f}, matte {m['fg_matte_iou']:.3f}")
    imgs.append(iio.imread(os.path.join(out, f"view{view:03d}_bg.png"))[..., :3])
iio.imwrite(sheet, np.concatenate(imgs, axis=1))
