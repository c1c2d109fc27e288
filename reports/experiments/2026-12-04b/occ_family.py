"""The default row of the family scenes rescored as their runs render (FAMILY_occupancy_metrics.json, today's
bench/strategies.py on refits of the committed fits) against the committed rows (reports/family.json), and
each half's summary as the report judges it (mi_voldis.bench.family.summary).

    python occ_family.py                  (from the checkout's root or anywhere; the package importable)
"""
import copy
import glob
import json
import os

import numpy as np

from mi_voldis.bench.family import scene_row, summary

HERE = os.path.dirname(os.path.abspath(__file__))
committed = json.load(open(os.path.join(HERE, "..", "..", "family.json")))
after = copy.deepcopy(committed)
rescored = {}
for path in sorted(glob.glob(os.path.join(HERE, "family*_occupancy_metrics.json"))):
    scene = os.path.basename(path).split("_")[0]
    m = json.load(open(path))
    after["scenes"][scene]["strategies"]["guided"] = m
    rescored[scene] = (scene_row(committed["scenes"][scene], "guided"), scene_row(after["scenes"][scene], "guided"))
for scene, (a, b) in rescored.items():
    print(f"{scene} ({committed['scenes'][scene]['half']}): margin {a['margin']:+.2f} -> {b['margin']:+.2f}, "
          f"consistency margin {a['consistency_margin']:+.2f} -> {b['consistency_margin']:+.2f}, "
          f"IoU {a['coverage_iou']:.3f} -> {b['coverage_iou']:.3f}, haze in hole {a['haze_mask']:.3f} -> {b['haze_mask']:.3f}")
for half in ("tuning", "check"):
    scenes = [s for s in rescored if committed["scenes"][s]["half"] == half]
    if not scenes:
        continue
    part = {"scenes": {s: committed["scenes"][s] for s in scenes}}
    new = {"scenes": {s: after["scenes"][s] for s in scenes}}
    a, b = summary(part, "guided", half), summary(new, "guided", half)
    print(f"{half} half, the {len(scenes)} rescored scenes: worst {a['worst'][0]} {a['worst'][1]:+.2f} -> "
          f"{b['worst'][0]} {b['worst'][1]:+.2f}; median {np.median(a['margins']):+.2f} -> {np.median(b['margins']):+.2f}; "
          f"meeting every target {len(a['met'])} -> {len(b['met'])} ({', '.join(sorted(b['met']))})")
