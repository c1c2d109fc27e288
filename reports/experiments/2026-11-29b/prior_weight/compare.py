"""Background-only refits of the family (run.sh) beside the committed default rows (reports/family.json).

    python reports/experiments/2026-11-29b/prior_weight/compare.py OUT/pwW [BASE.json]

Per scene: margin over max(Telea, Navier-Stokes) in the mask, the consistency margin, coverage IoU and haze
(in the hole / outside), default -> refit; then each half's worst margin, how many scenes gained, and how many
meet every target (margin >= +2, consistency margin >= +3, coverage IoU >= 0.9: as reports/removal.md counts
them, mi_voldis.bench.family.summary).
"""
import json
import os
import sys

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4)))

from mi_voldis.bench.family import scene_row  # noqa: E402


def meets(r):
    return r["margin"] >= 2.0 and r["consistency_margin"] >= 3.0 and (r["coverage_iou"] or 0) >= 0.9


def main(out, base_path="reports/family.json"):
    with open(base_path) as f:
        base = json.load(f)["scenes"]
    halves = {}
    for scene in sorted(base):
        path = os.path.join(out, scene, "metrics.json")
        if not os.path.isfile(path):
            continue
        with open(path) as f:
            new = scene_row({"strategies": {"guided": json.load(f)}}, "guided")
        old, half = scene_row(base[scene], "guided"), base[scene]["half"]
        halves.setdefault(half, []).append((scene, old, new))
        print(f"{scene} {half:6s} margin {old['margin']:+.2f} -> {new['margin']:+.2f} "
              f"({new['margin'] - old['margin']:+.2f})"
              f" | consistency {old['consistency_margin']:+.2f} -> {new['consistency_margin']:+.2f} | IoU "
              f"{old['coverage_iou']:.2f} -> {new['coverage_iou']:.2f} | haze {old['haze_mask']:.3f}/"
              f"{old['haze_outside']:.3f} -> {new['haze_mask']:.3f}/{new['haze_outside']:.3f}")
    if not halves:
        sys.exit(f"{out}: no refitted family scene (SCENE/metrics.json)")
    for half, rows in halves.items():
        w0 = min(rows, key=lambda r: r[1]["margin"])
        w1 = min(rows, key=lambda r: r[2]["margin"])
        d = [r[2]["margin"] - r[1]["margin"] for r in rows]
        print(f"{half} half ({len(rows)} scenes): worst {w0[0]} {w0[1]['margin']:+.2f} -> "
              f"{w1[0]} {w1[2]['margin']:+.2f}; "
              f"margin up on {sum(x > 0 for x in d)}, down on {sum(x < 0 for x in d)}, mean change "
              f"{sum(d) / len(d):+.3f} dB; every target met on {sum(meets(r[1]) for r in rows)} -> "
              f"{sum(meets(r[2]) for r in rows)}")


if __name__ == "__main__":
    main(*sys.argv[1:])
