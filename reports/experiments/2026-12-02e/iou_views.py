"""#46: where the removal family's foreground coverage IoU falls under 0.9, view by view, beside the full
field's held-out PSNR in the same view (read from a bench report's family.json; nothing is rendered).

    python iou_views.py reports/family.json
"""
import numpy as np
from family_report import scenes_from_argv

scenes = scenes_from_argv(__doc__, __file__)
low, high = [], []
for name, e in sorted(scenes.items()):
    views = e["fit"]["metrics"]["per_view"]
    iou = e["strategies"]["guided"]["methods"]["volume"]["fg_coverage_iou"]
    median = np.median([v["psnr"] for v in views])
    cells = " ".join(f"v{v['view']} {v['psnr']:.1f}/{v['fg_coverage_iou']:.2f}" for v in views)
    print(f"{name} {e['half']:6s} {e['kind']:8s} IoU {iou:.2f} | full field dB / IoU by view: {cells}")
    for v in views:
        (low if v["fg_coverage_iou"] < 0.9 else high).append(v["psnr"] - median)
print(f"views under IoU 0.9: {len(low)}, their full field {np.median(low):+.2f} dB from their scene's median view "
      f"(median); views at 0.9 or more: {len(high)}, {np.median(high):+.2f}")
off = [d for d in low if d < -3]
print(f"views under IoU 0.9 whose full field is more than 3 dB under their scene's median: {len(off)}")
