"""The removal rows of a run.sh variant (ROWS=1) against the committed default's (out/fam_split), scored as
reports/removal.md scores them: in-mask PSNR and its margin over max(Telea, Navier-Stokes), the consistency
margin over the best 2D method, coverage IoU and haze.

    python reports/experiments/2026-11-27/lr_views/rows.py NAME 06 00 02 04
"""
import json
import os
import sys


def row(scene, label, path):
    with open(path) as f:
        m = json.load(f)["methods"]
    v = m["volume"]
    classic = max(m["telea"]["psnr_mask"], m["ns"]["psnr_mask"])
    best_2d = max(m[x]["consistency_psnr"] for x in m if x != "volume")
    return (f"{scene} {label}: in mask {v['psnr_mask']:.2f} margin {v['psnr_mask'] - classic:+.2f} "
            f"consistency {v['consistency_psnr'] - best_2d:+.2f} coverage {v.get('fg_coverage_iou'):.3f} "
            f"haze {v['bg_haze_mask']:.3f}/{v['bg_haze_outside']:.3f}")


def main(name, scenes):
    for k in scenes:
        for label, path in (("default", f"out/fam_split/removal/family{k}/guided/metrics.json"),
                            (name, f"out/lrv/removal/family{k}/{name}/metrics.json")):
            if os.path.exists(path):
                print(row(f"family{k}", label, path))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
