"""The session's family rows (row `guided`) side by side, default against `--set free_space=true`:
python session_rows.py BENCH [BASE_WORK ...]

BENCH: the folder holding `def/SCENE/work` and `told/SCENE/work` (one `bench.py --family --scenes SCENE --work
...` each; `told`: `--set free_space=true` at fd4c9bc). BASE_WORK: earlier `--work` folders whose default rows
stand in for scenes this session did not fit with the default (the tuning half, fitted at 5bbba03, whose default
rows the code since leaves unchanged). Columns: margin over the better of Telea / Navier-Stokes in the mask,
consistency margin, coverage IoU, haze in the hole / outside; each half's worst of the scenes with both rows.
"""
import glob
import json
import os
import sys

from mi_voldis.bench.family import scene_row
from mi_voldis.synth.family import CHECK


def rows(pattern):
    out = {}
    for f in sorted(glob.glob(pattern)):
        scene = f.split(os.sep)[-3]
        with open(f) as fh:
            out[scene] = scene_row({"strategies": {"guided": json.load(fh)}}, "guided")
    return out


def cell(r):
    if r is None:
        return "-"
    c = r["consistency_margin"]
    return (f"{r['margin']:+.2f}, {'-' if c is None else f'{c:+.2f}'}, {r['coverage_iou']:.2f}, "
            f"{r['haze_mask']:.3f} / {r['haze_outside']:.3f}")


bench = sys.argv[1]
default = rows(os.path.join(bench, "def", "*", "work", "removal", "*", "guided", "metrics.json"))
for base in sys.argv[2:]:
    for scene, r in rows(os.path.join(base, "removal", "*", "guided", "metrics.json")).items():
        default.setdefault(scene, r)
told = rows(os.path.join(bench, "told", "*", "work", "removal", "*", "guided", "metrics.json"))
print("| scene | half | default | free_space=true |")
print("|---|---|---|---|")
for scene in sorted(set(default) | set(told)):
    half = "check" if int(scene[-2:]) in CHECK else "tuning"
    print(f"| {scene} | {half} | {cell(default.get(scene))} | {cell(told.get(scene))} |")
for half in ("tuning", "check"):
    both = [s for s in told if s in default and (half == "check") == (int(s[-2:]) in CHECK)]
    if both:
        worst = min(both, key=lambda s: default[s]["margin"])
        low = min(both, key=lambda s: told[s]["margin"])
        print(f"{half} half, {len(both)} scenes with both rows: worst default {worst} {default[worst]['margin']:+.2f}, "
              f"worst free_space {low} {told[low]['margin']:+.2f}")
