"""The scene rule with strides at three stops (transmittance 1e-3, 3e-3, 1e-2): held-out PSNR, samples a ray.

    python stop.py RUN [--views N]
"""
import sys

import drjit as dr
import numpy as np
from common import fitted_run

from mi_voldis.metrics import psnr
from mi_voldis.render.views import render_camera

run, ds, tests, res, _ = fitted_run(sys.argv[1:])
for stop in (1e-3, 3e-3, 1e-2):
    integ = run.integrator(occupancy_resolution=res - 1, stop_transmittance=stop, strides=True)
    with dr.suspend_grad():
        out = {v: render_camera(integ, ds.cameras[v], ("full", "bg")) for v in tests}
    ev = np.concatenate([out[v]["evaluated"].ravel() for v in tests])
    held = np.mean([psnr(np.clip(ds.as_photographed(out[v]["full"]), 0, 1), ds.images[v]) for v in tests])
    print(f"stop {stop:g}: held out {held:.4f} dB, samples a ray {ev.mean():.1f}", flush=True)
