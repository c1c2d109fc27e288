"""A family trial's scenes beside the default's committed ones (reports/family.json), scene by scene.

    python reports/experiments/2026-11-28/family_tv2/compare.py WORK [BASE.json]

WORK: the --work folder of `python scripts/bench.py --family --set ... --work WORK --report DIR` (read while
it runs: every scene whose `guided` row is done). Prints, per scene: the full field's held-out PSNR and
grid, the margin over max(Telea, Navier-Stokes) in the mask, the consistency margin, coverage IoU and haze
(in the hole / outside), default -> trial; then each half's worst margin and how many scenes gained.
"""
import json
import os
import sys

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4)))

from mi_voldis.bench.family import scene_row  # noqa: E402


def main(work, base_path="reports/family.json"):
    with open(base_path) as f:
        base = json.load(f)["scenes"]
    deltas = {"tuning": [], "check": []}
    worst = {"tuning": [None, None], "check": [None, None]}
    for scene in sorted(base):
        row = os.path.join(work, "removal", scene, "guided", "metrics.json")
        fit = os.path.join(work, "runs", f"{scene}_0", "metrics.json")
        if not (os.path.isfile(row) and os.path.isfile(fit)):
            continue
        with open(row) as f:
            new = scene_row({"strategies": {"guided": json.load(f)}}, "guided")
        with open(fit) as f:
            new_fit = json.load(f)
        old, old_fit, half = scene_row(base[scene], "guided"), base[scene]["fit"]["metrics"], base[scene]["half"]
        deltas[half].append(new["margin"] - old["margin"])
        for k, r in enumerate((old, new)):
            if worst[half][k] is None or r["margin"] < worst[half][k][1]:
                worst[half][k] = (scene, r["margin"])
        print(f"{scene} {half:6s} full {old_fit['held_out']['psnr']:6.2f} -> {new_fit['held_out']['psnr']:6.2f} dB, "
              f"{old_fit['grid']['full'][0]} -> {new_fit['grid']['full'][0]} | margin {old['margin']:+.2f} -> "
              f"{new['margin']:+.2f} ({new['margin'] - old['margin']:+.2f}) | consistency "
              f"{old['consistency_margin']:+.2f} -> {new['consistency_margin']:+.2f} | IoU "
              f"{old['coverage_iou']:.2f} -> {new['coverage_iou']:.2f} | haze {old['haze_mask']:.3f}/"
              f"{old['haze_outside']:.3f} -> {new['haze_mask']:.3f}/{new['haze_outside']:.3f}")
    if not any(deltas.values()):
        sys.exit(f"{work}: no family scene with a finished fit and `guided` row (runs/SCENE_0, removal/SCENE/guided)")
    for half, d in deltas.items():
        if d:
            (s0, m0), (s1, m1) = worst[half]
            print(f"{half} half ({len(d)} scenes): worst {s0} {m0:+.2f} -> {s1} {m1:+.2f}; margin up on "
                  f"{sum(x > 0 for x in d)}, down on {sum(x < 0 for x in d)}; mean change {sum(d) / len(d):+.3f} dB")


if __name__ == "__main__":
    main(*sys.argv[1:])
