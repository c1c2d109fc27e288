"""How a fitted run's evaluated samples a ray are spread (scene rule, strides; stop given): percentiles,
and the share of all samples taken by the rays past each percentile.

    python where.py RUN [--views N] STOP
"""
import os
import sys

import drjit as dr
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-12-04d"))
from common import fitted_run  # noqa: E402  (2026-12-04d's: the run and its held-out views)

from mi_voldis.render.views import render_camera

run, ds, tests, res, rest = fitted_run(sys.argv[1:])
integ = run.integrator(occupancy_resolution=res - 1, stop_transmittance=float(rest[0]), strides=True)
with dr.suspend_grad():
    ev = np.concatenate([render_camera(integ, ds.cameras[v], ("full",))["evaluated"].ravel() for v in tests])
ev = np.sort(ev.astype(np.float64))
print(f"mean {ev.mean():.1f}; percentiles 10/50/75/90/99: {np.percentile(ev, [10, 50, 75, 90, 99]).round(1)}")
for q in (50, 75, 90):
    cut = np.percentile(ev, q)
    print(f"rays above the {q}th percentile ({cut:.0f}) take {ev[ev > cut].sum() / ev.sum():.1%} of the samples")
