"""Held-out figures of finished runs, and per view against a reference run's metrics.json.

usage: python compare.py REFERENCE_METRICS_JSON LABEL=RUN ...
"""
import json
import os
import sys

ref = json.load(open(sys.argv[1]))
for item in sys.argv[2:]:
    label, run = item.split("=", 1)
    m = json.load(open(os.path.join(run, "metrics.json")))
    h, s = m["held_out"], m["schedule"]
    plan = s.get("plan") or {}
    diffs = [a["psnr"] - b["psnr"] for a, b in zip(m["per_view"], ref["per_view"])]
    print(f"{label}: {h['psnr']:.3f} dB, SSIM {h['ssim']:.3f}, haze {h['haze']:.3f}, grid {m['grid']['full'][0]}^3, "
          f"{s['steps_full']} steps, step {plan.get('step_voxels')} voxel, "
          f"{m['evaluated_samples_per_ray']:.0f} samples a ray, peak RSS {m['peak_rss_mib'] / 1024:.2f} GiB, "
          f"bounds {plan.get('resolution_bounds')}, caps {plan.get('memory_caps')}; against the reference: "
          f"{sum(d > 0 for d in diffs)} of {len(diffs)} views higher ({min(diffs):+.2f} to {max(diffs):+.2f} dB)")
