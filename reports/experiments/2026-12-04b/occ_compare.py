"""The default row of four family scenes scored on the fields marched without the run's occupancy grid
(before: FAMILY_plate_metrics.json, written by the plate trial's code, its 'plate' row dropped here) and
as the run's scene.xml renders them (after: FAMILY_occupancy_metrics.json, today's strategies.py).

    python occ_compare.py family22 family04 family06 family20      (from this folder, the package importable)
"""
import json
import os
import sys

from mi_voldis.bench.family import scene_row

HERE = os.path.dirname(os.path.abspath(__file__))
for scene in sys.argv[1:]:
    rows = []
    for tag in ("plate", "occupancy"):
        m = json.load(open(os.path.join(HERE, f"{scene}_{tag}_metrics.json")))
        m["methods"].pop("plate", None)  # the trial's row, not a 2D method
        rows.append(scene_row({"strategies": {"guided": m}}, "guided"))
    a, b = rows
    print(f"{scene}: in mask {a['psnr_mask']:.2f} -> {b['psnr_mask']:.2f} (margin {a['margin']:+.2f} -> "
          f"{b['margin']:+.2f}); consistency margin {a['consistency_margin']:+.2f} -> {b['consistency_margin']:+.2f}; "
          f"IoU {a['coverage_iou']:.3f} -> {b['coverage_iou']:.3f}; haze {a['haze_mask']:.3f}/{a['haze_outside']:.3f}"
          f" -> {b['haze_mask']:.3f}/{b['haze_outside']:.3f}; residue {a['residue']:.3f} -> {b['residue']:.3f}")
