"""A removal-family run scored as fit.report.evaluate scores a finished fit, under the old scene rule (occupancy
cells of four voxels, stop at transmittance 1e-4) and today's (cells of one voxel, stop at 1e-3): held-out PSNR,
the background's PSNR in the dilated masks against the true background, its haze in and outside them, the
foreground's coverage IoU, samples a ray.

    python rules_family.py RUN
"""
import sys

import numpy as np
from common import fitted_run

from mi_voldis.fit.report import evaluate

run, ds, _, res, _ = fitted_run(sys.argv[1:])
for label, cells, stop in (("old rule", int(np.ceil((res - 1) / 4)), 1e-4), ("scene rule", res - 1, 1e-3)):
    summary, _, _ = evaluate(ds, run.integrator(occupancy_resolution=cells, stop_transmittance=stop))
    print(f"{label}: held out {summary['psnr']:.4f}, bg in mask {summary.get('bg_psnr_mask', float('nan')):.4f} dB, "
          f"haze in / out {summary.get('bg_haze_mask', float('nan')):.4f} / "
          f"{summary.get('bg_haze_outside', float('nan')):.4f}, coverage IoU {summary.get('fg_coverage_iou', 0):.3f}, "
          f"samples a ray {summary['samples_per_ray']:.1f}", flush=True)
