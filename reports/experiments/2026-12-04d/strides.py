"""#42: a fitted run's held-out views rendered with today's scene rule (occupancy cells of one voxel, rays stopped
at transmittance 1e-3) without and with the voldis integrator's ``strides`` (render only, no refit). Prints held-out
PSNR against the photographs, the strided render's fidelity to the plain one, and evaluated samples a ray.

    python strides.py RUN [--views N]
"""
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
import drjit as dr  # noqa: E402

from mi_voldis.metrics import psnr  # noqa: E402
from mi_voldis.render.views import render_camera  # noqa: E402
from mi_voldis.tasks.base import FittedRun  # noqa: E402

args = sys.argv[1:]
nviews = None
if "--views" in args:
    i = args.index("--views")
    nviews = int(args[i + 1])
    del args[i:i + 2]
run = FittedRun(args[0])
ds = run.dataset
tests = list(ds.test)
if nviews and len(tests) > nviews:
    tests = [tests[i] for i in np.linspace(0, len(tests) - 1, nviews).round().astype(int)]
res = max(run.fields["full"].shape)
print(f"{args[0]}: grid {res}, views {tests}", flush=True)
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
