"""A removal row's margin over the better of Telea / Navier-Stokes, consistency margin, coverage IoU, haze in the
hole / outside and per-view margins, from each given metrics.json (`mi_voldis.bench.strategies`).

    python per_view.py METRICS.json ...
"""
import json
import sys

import numpy as np

for path in sys.argv[1:]:
    with open(path) as f:
        m = json.load(f)["methods"]
    v = m["volume"]
    per_view = np.array(v["psnr_mask_views"]) - np.maximum(m["telea"]["psnr_mask_views"], m["ns"]["psnr_mask_views"])
    best_c = max(m[n]["consistency_psnr"] for n in m if n != "volume" and m[n]["consistency_psnr"] is not None)
    classic = max(m[n]["psnr_mask"] for n in ("telea", "ns"))
    print(f"{path.rsplit('/', 1)[0][-48:]:48s} margin {v['psnr_mask'] - classic:+.2f} "
          f"cons {v['consistency_psnr'] - best_c:+.2f} IoU {v['fg_coverage_iou']:.3f} "
          f"haze {v['bg_haze_mask']:.3f}/{v['bg_haze_outside']:.3f} views {np.round(per_view, 2)}")
