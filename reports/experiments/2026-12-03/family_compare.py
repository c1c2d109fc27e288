"""#46: a trial's family.json against the committed default's, scene by scene: the full field held out, its held-out
views and coverage IoU, and the removal's margins (the report's own row, bench.family.scene_row).

    python family_compare.py DEFAULT_FAMILY_JSON LABEL=TRIAL_FAMILY_JSON [LABEL=TRIAL_FAMILY_JSON ...]
"""
import json
import os
import sys

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 3)))

from mi_voldis.bench.family import _f, scene_row  # noqa: E402

if len(sys.argv) < 3 or not all("=" in a for a in sys.argv[2:]):
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())


def load(path):
    try:
        with open(path) as f:
            return json.load(f)["scenes"]
    except (OSError, ValueError, KeyError) as e:
        raise SystemExit(f"family_compare.py: {path}: not a family report ({e})") from None


def line(label, entry):
    m, r = entry["fit"]["metrics"], scene_row(entry, "guided")
    views = " / ".join(f"{v['psnr']:.2f}" for v in m["per_view"])
    iou = " / ".join(f"{v['fg_coverage_iou']:.2f}" for v in m["per_view"])
    return (f"| {label} | {m['held_out']['psnr']:.3f} | {views} | {iou} | {r['coverage_iou']:.3f} | "
            f"{r['margin']:+.2f} | {_f(r['consistency_margin'], sign=True)} | "
            f"{r['haze_mask']:.3f} / {r['haze_outside']:.3f} |")


default = load(sys.argv[1])
trials = [(a.split("=", 1)[0], load(a.split("=", 1)[1])) for a in sys.argv[2:]]
print("| scene, run | held out | held-out views | IoU by view | coverage IoU | margin | consistency margin |"
      " haze in / out |")
print("|---|---|---|---|---|---|---|---|")
for scene in sorted({s for _, t in trials for s in t}):
    print(line(f"{scene} default", default[scene]))
    for label, t in trials:
        if scene in t:
            print(line(f"{scene} {label}", t[scene]))
