"""One line per strategies output folder: python show.py OUT [OUT ...]."""
import json
import sys

for d in sys.argv[1:]:
    m = json.load(open(d + "/metrics.json"))["methods"]["volume"]
    s = m.get("mask_surfaces", {})
    print(f"{d:40s} mask {m['psnr_mask']:.2f} seen/unseen {m['psnr_seen']:.2f}/{m['psnr_unseen']:.2f} "
          f"out {m['psnr_outside']:.2f} res {m['residue']:.2f} cons {m['consistency_psnr']:.2f} "
          f"iou {m['fg_coverage_iou']:.2f} hull {s.get('in_hull', 0):.2f} at {s.get('background', 0):.2f} "
          f"ring {s.get('ring', 0):.2f}")
