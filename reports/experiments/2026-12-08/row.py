"""The family numbers of `guided` rows, one line each: python row.py METRICS.json [...]
(margin over the better of Telea / Navier-Stokes in the mask, the same outside it, consistency margin, coverage IoU,
haze in the hole / outside, PSNR in the mask)."""
import json
import sys

from mi_voldis.bench.family import scene_row

for path in sys.argv[1:]:
    with open(path) as f:
        r = scene_row({"strategies": {"guided": json.load(f)}}, "guided")
    print(f"{path}: margin {r['margin']:+.2f} outside {r['outside_margin']:+.2f} cons {r['consistency_margin']:+.2f} "
          f"iou {r['coverage_iou']:.3f} haze {r['haze_mask']:.3f}/{r['haze_outside']:.3f} psnr {r['psnr_mask']:.3f}")
