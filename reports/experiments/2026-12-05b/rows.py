"""One row per finished fit, each against the first (the baseline), from the runs' metrics.json.

    python reports/experiments/2026-12-05b/rows.py NAME=RUN [NAME=RUN ...]

RUN: a run folder, or a metrics.json (a committed copy of one).

Prints held-out PSNR and SSIM, the final grid, steps, samples a ray as the scene renders, the fit's seconds
and peak RSS, and on how many held-out views the run beats the baseline (with the least and most change).
"""
import json
import os
import sys

import numpy as np


def load(path):
    with open(path if path.endswith(".json") else os.path.join(path, "metrics.json")) as f:
        return json.load(f)


runs = [arg.split("=", 1) for arg in sys.argv[1:]]
base = {v["view"]: v["psnr"] for v in load(runs[0][1])["per_view"]}
print("| run | held out | SSIM | grid | steps | samples a ray | fit s | peak RSS MiB | views higher than "
      f"{runs[0][0]} (min / max change) |")
print("|---|---|---|---|---|---|---|---|---|")
for name, path in runs:
    m = load(path)
    change = np.array([v["psnr"] - base[v["view"]] for v in m["per_view"]])
    print(f"| {name} | {m['held_out']['psnr']:.3f} | {m['held_out']['ssim']:.3f} | {m['grid']['full'][0]}^3 | "
          f"{m['schedule']['steps_full']} | {m['held_out']['samples_per_ray']:.1f} | {m['seconds']['fit']:.0f} | "
          f"{m['peak_rss_mib']:.0f} | {(change > 0).sum()} of {len(change)} ({change.min():+.2f} / "
          f"{change.max():+.2f}) |")
