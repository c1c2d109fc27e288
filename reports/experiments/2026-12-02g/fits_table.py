"""#46/#42: the full fields of several runs of one scene side by side, from their metrics.json: held-out PSNR,
per view, the foreground coverage IoU by view and overall, the grid and the samples a ray.

    python fits_table.py LABEL=RUN [LABEL=RUN ...]
"""
import json
import os
import sys

if len(sys.argv) < 2 or not all("=" in a for a in sys.argv[1:]):
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
print("| run | held out | by view | coverage IoU by view | coverage IoU | grid | samples a ray |")
print("|---|---|---|---|---|---|---|")
for arg in sys.argv[1:]:
    label, run = arg.rsplit("=", 1)
    path = os.path.join(run, "metrics.json")
    try:
        m = json.load(open(path))
        h, views, grid = m["held_out"], m["per_view"], m["grid"]["full"]
    except (OSError, ValueError, KeyError) as e:
        raise SystemExit(f"fits_table.py: {path}: not a finished run's metrics ({e})") from None
    print(f"| {label} | {h['psnr']:.3f} | " + " / ".join(f"{v['psnr']:.2f}" for v in views)
          + " | " + " / ".join(f"{v['fg_coverage_iou']:.2f}" for v in views)
          + f" | {h['fg_coverage_iou']:.3f} | {'x'.join(map(str, grid))} | {m['evaluated_samples_per_ray']:.0f} |")
