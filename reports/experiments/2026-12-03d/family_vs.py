"""A trial's removal-family rows against the committed report's, scene by scene: the full field held out, and
for the guided background the margin over the better of Telea and Navier-Stokes in the mask, the consistency
margin over the best 2D method's and the coverage IoU (#46's three targets: +2 dB, +3 dB, 0.9).

usage: python family_vs.py REFERENCE_FAMILY_JSON TRIAL_FAMILY_JSON...
"""
import json
import sys

from mi_voldis.bench.family import TARGET_CONSISTENCY, TARGET_IOU, TARGET_MARGIN, scene_row

if len(sys.argv) < 3:
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
tables = []
for path in sys.argv[1:]:
    try:
        with open(path) as f:
            tables.append(json.load(f)["scenes"])
    except (OSError, ValueError, KeyError) as e:
        raise SystemExit(f"family_vs.py: {path}: not a family report ({e})") from None
ref, trials = tables[0], {}
for table in tables[1:]:
    trials.update(table)


def line(entry):
    row = scene_row(entry, "guided")
    full = entry["fit"]["metrics"]["held_out"]["psnr"]
    met = (row["margin"] >= TARGET_MARGIN and row["consistency_margin"] is not None
           and row["consistency_margin"] >= TARGET_CONSISTENCY and row["coverage_iou"] >= TARGET_IOU)
    cons = "n/a" if row["consistency_margin"] is None else f"{row['consistency_margin']:+.2f}"
    return f"full {full:.3f}, margin {row['margin']:+.2f}, consistency {cons}, IoU {row['coverage_iou']:.3f}" + \
        (", every target" if met else "")


for scene in sorted(trials):
    if scene not in ref:
        raise SystemExit(f"family_vs.py: {scene} is not in {sys.argv[1]}")
    print(f"{scene} ({ref[scene]['half']}, {ref[scene]['kind']}): reference {line(ref[scene])}")
    print(f"{' ' * len(scene)}  trial:     {line(trials[scene])}")
