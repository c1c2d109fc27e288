"""A fitted run rendered by its scene rule (one-voxel occupancy cells, strides) at the stops given:
held-out PSNR, SSIM, and evaluated samples a ray, every held-out view (or N spread over them).

    python stop.py RUN [--views N] STOP[,STOP...]
"""
import os
import sys

import drjit as dr
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-12-04d"))
from common import fitted_run  # noqa: E402  (2026-12-04d's: the run and its held-out views)

from mi_voldis.metrics import psnr, ssim
from mi_voldis.render.views import render_camera

run, ds, tests, res, rest = fitted_run(sys.argv[1:])
for stop in [float(s) for s in rest[0].split(",")]:
    integ = run.integrator(occupancy_resolution=res - 1, stop_transmittance=stop, strides=True)
    with dr.suspend_grad():
        out = {v: render_camera(integ, ds.cameras[v], ("full",)) for v in tests}
    ev = np.concatenate([out[v]["evaluated"].ravel() for v in tests])
    imgs = {v: np.clip(ds.as_photographed(out[v]["full"]), 0, 1) for v in tests}
    held = np.mean([psnr(imgs[v], ds.images[v]) for v in tests])
    sim = np.mean([ssim(imgs[v], ds.images[v]) for v in tests])
    print(f"stop {stop:g}: held out {held:.4f} dB, SSIM {sim:.4f}, samples a ray {ev.mean():.1f}", flush=True)
