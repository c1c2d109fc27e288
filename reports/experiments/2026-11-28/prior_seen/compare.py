"""#46 trials: each family scene's `guided` row refitted under a trial (screen.sh's OUT) against the same rows
under today's default (BASE: a screen.sh folder; rows it lacks are read from BENCH_WORK/removal/SCENE/guided).
    python reports/experiments/2026-11-28/prior_seen/compare.py BASE TRIAL [BENCH_WORK]"""
import json
import os
import sys


def row(path):
    """(margin over the better of Telea / NS, consistency margin, coverage IoU, haze in / out, unseen, seen PSNR)."""
    m = json.load(open(path))["methods"]
    v = m["volume"]
    best = max(m["telea"]["psnr_mask"], m["ns"]["psnr_mask"])
    best_c = max(m[k]["consistency_psnr"] for k in m if k != "volume")
    return (v["psnr_mask"] - best, v["consistency_psnr"] - best_c, v["fg_coverage_iou"], v["bg_haze_mask"],
            v["bg_haze_outside"], v.get("psnr_unseen"), v.get("psnr_seen"))


def find(base, scene):
    for path in (f"{base}/{scene}/metrics.json", f"{base}/removal/{scene}/guided/metrics.json"):
        if os.path.exists(path):
            return path
    return None


def main(base, trial, bench=None):
    for scene in sorted(os.listdir(trial)):
        after = find(trial, scene)
        before = find(base, scene) or (find(bench, scene) if bench else None)
        if not after or not before:
            continue
        x, y = row(before), row(after)
        print(f"{scene}: margin {x[0]:+.2f} -> {y[0]:+.2f} ({y[0] - x[0]:+.2f}) cons {x[1]:+.2f} -> {y[1]:+.2f} "
              f"iou {x[2]:.2f}->{y[2]:.2f} haze {x[3]:.3f}/{x[4]:.3f} -> {y[3]:.3f}/{y[4]:.3f} "
              f"unseen {x[5]:.2f}->{y[5]:.2f} seen {x[6]:.2f}->{y[6]:.2f}")


if __name__ == "__main__":
    main(*sys.argv[1:])
