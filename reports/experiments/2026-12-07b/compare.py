"""Rows of fits against a reference fit, from their metrics.json files: held-out PSNR and its change, how many
held-out views score higher (and the smallest / largest change of a view), the last grid, the full phase's
steps, evaluated and training samples a ray, peak RSS and the carve's tightenings.

    python reports/experiments/2026-12-07b/compare.py REFERENCE_METRICS METRICS...
"""
import json
import os
import sys


def row(ref, run, name):
    diffs = [b["psnr"] - a["psnr"] for a, b in zip(ref["per_view"], run["per_view"])]
    p, q = run["held_out"]["psnr"], ref["held_out"]["psnr"]
    return (f"{name}: {p:.3f} dB against {q:.3f} ({p - q:+.3f}), {sum(d > 0 for d in diffs)} of {len(diffs)} views "
            f"higher ({min(diffs):+.2f} / {max(diffs):+.2f}); {run['grid']['full'][0]}^3, "
            f"{run['schedule']['steps_full']} steps, {run['evaluated_samples_per_ray']:.1f} samples a ray "
            f"({run['train_samples_per_ray']:.1f} training), {run['peak_rss_mib']:.0f} MiB, carve tightened "
            f"{run['schedule']['plan'].get('carve_tightened')}")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("compare.py: give a reference metrics.json and at least one more")
    ref = json.load(open(sys.argv[1]))
    for path in sys.argv[2:]:
        print(row(ref, json.load(open(path)), os.path.basename(path)))
