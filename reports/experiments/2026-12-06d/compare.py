"""Held-out PSNR per view, grid, steps, samples a ray and peak memory of run folders, side by side.

    python reports/experiments/2026-12-06d/compare.py BASE_RUN OTHER_RUN... (run folders or metrics.json files)
"""
import json
import sys
from pathlib import Path


def load(path):
    p = Path(path)
    return json.loads((p / "metrics.json" if p.is_dir() else p).read_text())


runs = [(arg, load(arg)) for arg in sys.argv[1:]]
base = runs[0][1]
for name, m in runs:
    views = {v["view"]: v["psnr"] for v in m["per_view"]}
    ref = {v["view"]: v["psnr"] for v in base["per_view"]}
    up = sum(views[k] > ref[k] for k in views)
    bricks = m.get("bricks", {}).get("full", {})
    print(f"{name}: {m['held_out']['psnr']:.3f} dB ({m['held_out']['psnr'] - base['held_out']['psnr']:+.3f}; "
          f"{up} of {len(views)} views higher), SSIM {m['held_out']['ssim']:.4f}, grid {m['grid']['full'][0]}^3, "
          f"{m['schedule']['steps_full']} steps, {bricks.get('vertices', 0) / 1e6:.2f} M vertices, "
          f"{m['held_out']['samples_per_ray']:.1f} samples a ray, peak RSS {m['peak_rss_mib']:.0f} MiB, "
          f"bg haze in / out of the mask {m['held_out'].get('bg_haze_mask', float('nan')):.3f} / "
          f"{m['held_out'].get('bg_haze_outside', float('nan')):.3f}")
    print("   per view: " + ", ".join(f"{k} {views[k]:.3f} ({views[k] - ref[k]:+.3f})" for k in sorted(views)))
