"""The last stage's median seconds and evaluated samples a training step of each run given, past its first
100 steps, with its held-out PSNR and evaluated samples per ray (step_cost.sh runs them).

    python reports/experiments/2026-11-27/step/step_cost.py RUN [RUN ...]
"""
import json
import sys

import numpy as np


def main(runs):
    base = None
    for run in runs:
        with open(f"{run}/log.json") as f:
            log = json.load(f)
        with open(f"{run}/metrics.json") as f:
            m = json.load(f)
        rows = log if isinstance(log, list) else log["log"]
        start = m["schedule"]["stages"][-1][0]
        last = [r for r in rows if r.get("phase") == "full" and r["step"] > start + 100 and "test_psnr" not in r]
        seconds = float(np.median([r["step_seconds"] for r in last]))
        samples = float(np.median([r["samples"] for r in last]))
        base = base or seconds
        print(f"{run}: {m['grid']['full'][0]}^3, {m['bricks']['full']['vertices']:,} vertices, "
              f"{seconds:.4f} s a step ({seconds / base:.3f} of the first run's), {samples:,.0f} samples a step, "
              f"held out {m['held_out']['psnr']:.3f} dB, {m['evaluated_samples_per_ray']:.0f} samples a ray")


if __name__ == "__main__":
    main(sys.argv[1:])
