"""The default background against a trial on family scenes whose committed rows are not in reports/family.json
(scenes added to the family): pairs of (OLD, NEW) removal folders, each holding SCENE/guided/metrics.json.

    python fresh.py OLD_REMOVAL NEW_REMOVAL SCENE...
"""
import json
import os
import sys

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4)))

from mi_voldis.bench.family import scene_row  # noqa: E402

old, new = sys.argv[1], sys.argv[2]
for scene in sys.argv[3:]:
    rows = []
    for base in (old, new):
        with open(os.path.join(base, scene, "guided", "metrics.json")) as f:
            rows.append(scene_row({"strategies": {"guided": json.load(f)}}, "guided"))
    a, b = rows
    print(f"{scene}: in the mask {a['psnr_mask']:.2f} -> {b['psnr_mask']:.2f} dB (Telea/NS best {a['classic']:.2f}), "
          f"margin {a['margin']:+.2f} -> {b['margin']:+.2f}, consistency margin {a['consistency_margin']:+.2f} -> "
          f"{b['consistency_margin']:+.2f}, IoU {a['coverage_iou']:.2f} -> {b['coverage_iou']:.2f}")
