"""Margins of the keep_seen variants against the default guided row, per scene (from the checkout):

    python reports/experiments/2026-11-26/keep_seen/table.py family00,family01,...

Margin: in-mask PSNR of the volume's background minus the better of OpenCV Telea / Navier-Stokes; then the
consistency PSNR, the foreground coverage IoU, the residue and the haze in the hole."""
import glob
import json
import os
import sys


def row(path):
    methods = json.load(open(path))["methods"]
    volume = methods["volume"]
    best_2d = max(methods[k]["psnr_mask"] for k in ("telea", "ns") if k in methods)
    return (volume["psnr_mask"] - best_2d, volume.get("consistency_psnr"), volume.get("fg_coverage_iou"),
            volume.get("residue"), volume.get("bg_haze_mask"))


FORMAT = "margin %+.2f cons %.2f iou %.2f residue %.2f haze %.3f"
for scene in sys.argv[1].split(","):
    base = row(f"out/bench/removal/{scene}/guided/metrics.json")
    print(scene, "guided", FORMAT % base)
    for path in sorted(glob.glob(f"out/exp/{scene}_*/metrics.json")):
        r = row(path)
        print(scene, os.path.basename(os.path.dirname(path))[len(scene) + 1:], FORMAT % r, "d %+.2f" % (r[0] - base[0]))
