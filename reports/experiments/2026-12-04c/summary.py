"""One line per finished run: held-out PSNR / SSIM / haze of the full field, training samples a ray, grid,
occupied share of the occupancy grid, peak RSS and fit seconds (from each run's metrics.json).

    python summary.py RUN ...
"""
import json
import sys

if len(sys.argv) < 2:
    sys.exit("usage: summary.py RUN ...")
for r in sys.argv[1:]:
    try:
        with open(r + "/metrics.json") as f:
            m = json.load(f)
        h = m["held_out"]
    except (OSError, ValueError, KeyError) as e:
        print(f"{r}: no finished run's metrics.json ({e})")
        continue
    print(f"{r}: held out {h['psnr']:.3f} dB, SSIM {h['ssim']:.3f}, haze {h['haze']:.3f}, samples a ray "
          f"{m['evaluated_samples_per_ray']:.1f}, grid {m['grid']['full'][0]}^3, "
          f"occupied {m['occupied_fraction']:.3f}, "
          f"peak RSS {m['peak_rss_mib']:.0f} MiB, fit {m['seconds']['fit']:.0f} s")
