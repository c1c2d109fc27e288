"""#42: a fitted run's held-out views rendered with today's scene rule (occupancy cells of one voxel, rays stopped
at transmittance 1e-3) without and with the voldis integrator's ``strides`` (render only, no refit). Prints held-out
PSNR against the photographs, the strided render's fidelity to the plain one, and evaluated samples a ray.

    python strides.py RUN [--views N]
"""
import sys

import drjit as dr
import numpy as np
from common import fitted_run

from mi_voldis.metrics import psnr
from mi_voldis.render.views import render_camera

run, ds, tests, res, _ = fitted_run(sys.argv[1:])
print(f"{sys.argv[1]}: grid {res}, views {tests}", flush=True)
out = {}
for strides in (False, True):
    integ = run.integrator(occupancy_resolution=res - 1, stop_transmittance=1e-3, strides=strides)
    with dr.suspend_grad():
        out[strides] = {v: render_camera(integ, ds.cameras[v], ("full", "bg")) for v in tests}
    ev = np.concatenate([out[strides][v]["evaluated"].ravel() for v in tests])
    held = np.mean([psnr(np.clip(ds.as_photographed(out[strides][v]["full"]), 0, 1), ds.images[v]) for v in tests])
    fid = {layer: np.mean([psnr(np.clip(out[strides][v][layer][0], 0, 1), np.clip(out[False][v][layer][0], 0, 1))
                           for v in tests]) for layer in ("full", "bg")}
    print(f"strides {strides}: held out {held:.4f} dB, fidelity full {fid['full']:.1f} bg {fid['bg']:.1f} dB, "
          f"samples a ray {ev.mean():.1f} (p90 {np.percentile(ev, 90):.0f})", flush=True)
