"""#46: each family scene's `guided` row in OUT (a refit of screen.sh, or the bench's own row where it was run
under the new default) against the committed reports/family.json (today's code refits those rows exactly).
    python reports/experiments/2026-11-28/hull_fill_vertical/compare.py OUT [BENCH_WORK]"""
import json
import os
import sys

BASE = json.load(open(os.path.join(os.path.dirname(__file__), "../../../family.json")))["scenes"]


def row(m):
    """(in-mask margin over the better of Telea / NS, consistency margin over the best 2D method, coverage IoU,
    haze in the hole, haze outside, residue, in-mask PSNR)."""
    methods = m["methods"]
    v = methods["volume"]
    best = max(methods["telea"]["psnr_mask"], methods["ns"]["psnr_mask"])
    best_c = max(methods[k]["consistency_psnr"] for k in ("telea", "ns", "fsr") if k in methods)
    return (v["psnr_mask"] - best, v["consistency_psnr"] - best_c, v["fg_coverage_iou"], v["bg_haze_mask"],
            v["bg_haze_outside"], v["residue"], v["psnr_mask"])


def main(out, bench=None):
    print("scene     half    margin before -> after (diff)  consistency margin  coverage IoU  haze hole/outside"
          "               residue     source")
    for scene in sorted(BASE):
        before = row(BASE[scene]["strategies"]["guided"])
        refit = os.path.join(out, scene, "metrics.json")
        benched = os.path.join(bench, "removal", scene, "guided", "metrics.json") if bench else ""
        if os.path.exists(refit):
            after, source = row(json.load(open(refit))), "refit"
        elif benched and os.path.exists(benched):
            after, source = row(json.load(open(benched))), "bench"
            if abs(after[6] - before[6]) < 1e-6:  # benched under the old default
                continue
        else:
            continue
        print(f"{scene}  {BASE[scene]['half']:6s}  {before[0]:+.2f} -> {after[0]:+.2f} ({after[0] - before[0]:+.2f})"
              f"            {before[1]:+.2f} -> {after[1]:+.2f}     {before[2]:.2f} -> {after[2]:.2f}"
              f"  {before[3]:.3f}/{before[4]:.3f} -> {after[3]:.3f}/{after[4]:.3f}"
              f"  {before[5]:.2f} -> {after[5]:.2f}  {source}")


if __name__ == "__main__":
    main(*sys.argv[1:3])
