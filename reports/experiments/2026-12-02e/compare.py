"""#46: the default background against a trial over the removal family, half by half, from pairs of removal
folders (each SCENE/guided/metrics.json, as bench.py --family and refit.sh write them), every scene found in
both; prints each scene's row and each half's worst scene, median and scenes meeting every target.

    python compare.py OLD_REMOVAL:NEW_REMOVAL [OLD_REMOVAL:NEW_REMOVAL ...]
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 3)))

from mi_voldis.bench.family import scene_row  # noqa: E402
from mi_voldis.synth import family  # noqa: E402

if len(sys.argv) < 2 or any(":" not in a for a in sys.argv[1:]):
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())


def row(folder, scene):
    with open(os.path.join(folder, scene, "guided", "metrics.json")) as f:
        return scene_row({"strategies": {"guided": json.load(f)}}, "guided")


def meets(r):
    return r["margin"] >= 2 and r["consistency_margin"] >= 3 and r["coverage_iou"] >= 0.9


pairs = {}
for arg in sys.argv[1:]:
    old, new = arg.split(":", 1)
    for folder in (old, new):
        if not os.path.isdir(folder):
            raise SystemExit(f"compare.py: {folder}: no such removal folder")
    for scene in sorted(os.listdir(new)):
        if os.path.isfile(os.path.join(old, scene, "guided", "metrics.json")) and \
                os.path.isfile(os.path.join(new, scene, "guided", "metrics.json")):
            pairs[scene] = (row(old, scene), row(new, scene))
for half in ("tuning", "check"):
    names = sorted(s for s in pairs if family.half(family.index(s)) == half)
    if not names:
        continue
    print(f"== {half} half ({len(names)} scenes): margin, consistency margin, coverage IoU, haze in / out; old -> new")
    for s in names:
        a, b = pairs[s]
        print(f"{s} {family.scene(family.index(s))[1]:8s} margin {a['margin']:+6.2f} -> {b['margin']:+6.2f} "
              f"({b['margin'] - a['margin']:+.2f})  cons {a['consistency_margin']:+6.2f} -> "
              f"{b['consistency_margin']:+6.2f}  IoU {a['coverage_iou']:.2f} -> {b['coverage_iou']:.2f}  "
              f"haze {a['haze_mask']:.3f}/{a['haze_outside']:.3f}"
              f" -> {b['haze_mask']:.3f}/{b['haze_outside']:.3f}  meets {int(meets(a))} -> {int(meets(b))}")
    for label, k in (("old", 0), ("new", 1)):
        m = {s: pairs[s][k]["margin"] for s in names}
        worst = min(m, key=m.get)
        print(f"  {label}: worst {worst} {m[worst]:+.2f}, median {np.median(list(m.values())):+.2f}, "
              f"meet every target {sum(meets(pairs[s][k]) for s in names)} of {len(names)}")
