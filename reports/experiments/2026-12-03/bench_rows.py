"""#46: the report's row of every scene a `bench.py --family` work folder has finished (its fit and its
`guided` removal), against the committed default's (reports/family.json), before the bench has written
its family.json (a stopped or unfinished bench).

    python bench_rows.py WORK [WORK ...]
"""
import glob
import json
import os
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 3))
sys.path.insert(0, ROOT)

from mi_voldis.bench.family import _f, scene_row  # noqa: E402

if len(sys.argv) < 2:
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
with open(os.path.join(ROOT, "reports", "family.json")) as f:
    base = json.load(f)["scenes"]
for work in sys.argv[1:]:
    found = sorted(glob.glob(os.path.join(work, "removal", "*", "guided", "metrics.json")))
    if not found:
        raise SystemExit(f"bench_rows.py: {work}: no finished removal row (removal/SCENE/guided/metrics.json)")
    for path in found:
        scene = path.split(os.sep)[-3]
        with open(path) as f:
            removal = json.load(f)
        with open(os.path.join(work, "runs", f"{scene}_0", "metrics.json")) as f:
            fit = json.load(f)
        r = scene_row({"strategies": {"guided": removal}, "fit": {"metrics": fit}}, "guided")
        b = scene_row(base[scene], "guided")
        print(f"{scene} ({fit['space']}): held out {base[scene]['fit']['metrics']['held_out']['psnr']:.3f} -> "
              f"{fit['held_out']['psnr']:.3f} | margin {b['margin']:+.2f} -> {r['margin']:+.2f} | consistency "
              f"margin {_f(b['consistency_margin'], sign=True)} -> {_f(r['consistency_margin'], sign=True)} | "
              f"coverage IoU {b['coverage_iou']:.2f} -> {r['coverage_iou']:.2f} | haze in / out "
              f"{b['haze_mask']:.3f} / {b['haze_outside']:.3f} -> {r['haze_mask']:.3f} / {r['haze_outside']:.3f}")
