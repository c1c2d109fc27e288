"""Held-out figures and per-view PSNR of garden fits side by side: python compare.py NAME=RUN ..."""
import json
import sys

runs = [a.split("=", 1) for a in sys.argv[1:]]
metrics = {name: json.load(open(f"{path}/metrics.json")) for name, path in runs}
print(f"{'fit':28s} {'PSNR':>7s} {'SSIM':>6s} {'haze':>6s} {'grid':>5s} {'samples':>7s} {'peak GiB':>8s}")
for name, m in metrics.items():
    h = m["held_out"]
    print(f"{name:28s} {h['psnr']:7.3f} {h['ssim']:6.3f} {h['haze']:6.3f} {m['grid']['full'][0]:5d} "
          f"{m['evaluated_samples_per_ray']:7.1f} {m['peak_rss_mib'] / 1024:8.2f}")
names = list(metrics)
print("\nper held-out view, PSNR:\nview " + " ".join(f"{n[:12]:>12s}" for n in names))
for rows in zip(*(metrics[n]["per_view"] for n in names)):
    print(f"{rows[0]['view']:4d} " + " ".join(f"{r['psnr']:12.2f}" for r in rows))
first = names[0]
for n in names[1:]:
    up = sum(b["psnr"] > a["psnr"] for a, b in zip(metrics[first]["per_view"], metrics[n]["per_view"]))
    print(f"{n}: higher than {first} on {up} of {len(metrics[n]['per_view'])} views")
