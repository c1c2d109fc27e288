"""Other sets of stride levels than march.STRIDES (patched in this process) with today's scene rule: held-out
PSNR, fidelity to the first set's render, evaluated samples a ray.

    python levels.py RUN [--views N] NAME ...   (NAME: a key of LEVELS; the first is the reference)
"""
import sys

import drjit as dr
import numpy as np
from common import fitted_run

from mi_voldis.metrics import psnr
from mi_voldis.render import march
from mi_voldis.render.views import render_camera

LEVELS = {"default": march.STRIDES,
          "plus30": march.STRIDES + ((30.0, 2, 0.9),),
          "plus16": ((0.03, 16, 13.5),) + march.STRIDES,
          "dense2": ((0.03, 8, 6.3), (0.3, 4, 2.0), (3.0, 2, 0.9), (30.0, 2, 0.9))}

run, ds, tests, res, names = fitted_run(sys.argv[1:])
ref = None
for name in names:
    march.STRIDES = LEVELS[name]
    integ = run.integrator(occupancy_resolution=res - 1, stop_transmittance=1e-3, strides=True)
    with dr.suspend_grad():
        out = {v: render_camera(integ, ds.cameras[v], ("full", "bg")) for v in tests}
    ref = ref or out
    ev = np.concatenate([out[v]["evaluated"].ravel() for v in tests])
    held = np.mean([psnr(np.clip(ds.as_photographed(out[v]["full"]), 0, 1), ds.images[v]) for v in tests])
    fid = np.mean([psnr(np.clip(out[v]["full"][0], 0, 1), np.clip(ref[v]["full"][0], 0, 1)) for v in tests])
    print(f"{name}: held out {held:.4f} dB, fidelity {fid:.1f} dB, samples a ray {ev.mean():.1f}", flush=True)
