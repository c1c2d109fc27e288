"""Per-view held-out PSNR of garden runs beside the first one's, and each run's held-out curve during the fit.

    python reports/experiments/2026-11-28/garden_views.py NAME=RUN NAME=RUN ...

RUN: a finished `scripts/train.py` run folder (metrics.json, log.json). The first run is the reference:
for every other, the views that gain and lose on it, and the largest gains.
"""
import json
import os
import sys


def main(*pairs):
    runs = []
    for pair in pairs:
        name, _, run = pair.partition("=")
        try:
            with open(os.path.join(run, "metrics.json")) as f:
                metrics = json.load(f)
            with open(os.path.join(run, "log.json")) as f:
                log = json.load(f)
        except (OSError, ValueError) as e:
            sys.exit(f"{run}: not a finished run ({e})")
        runs.append((name, metrics, log))
    ref_name, ref, _ = runs[0]
    for name, metrics, log in runs:
        views = [(v["view"], v["psnr"]) for v in metrics["per_view"]]
        print(f"{name}: {metrics['held_out']['psnr']:.3f} dB, SSIM {metrics['held_out']['ssim']:.3f}, "
              f"grid {metrics['grid']['full'][0]}^3, degree {metrics['sh_degree']}, "
              f"stages {metrics['schedule']['stages']}")
        print("  worst views: " + ", ".join(f"{v} {p:.2f}" for v, p in sorted(views, key=lambda x: x[1])[:3]))
        print("  held-out curve (step, dB): " + ", ".join(f"{r['step']} {r['test_psnr']:.2f}" for r in log
                                                        if "test_psnr" in r))
        if name != ref_name:
            d = [(v, p - q["psnr"]) for (v, p), q in zip(views, ref["per_view"])]
            print(f"  against {ref_name}: {sum(x > 0 for _, x in d)} of {len(d)} views gain; losses "
                  + ", ".join(f"{v} {x:+.2f}" for v, x in d if x <= 0) + "; largest gains "
                  + ", ".join(f"{v} {x:+.2f}" for v, x in sorted(d, key=lambda t: -t[1])[:3]))


if __name__ == "__main__":
    main(*sys.argv[1:])
