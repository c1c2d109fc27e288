"""One held-out view of a fitted run rendered by its scene rule at the stops given: the share of its pixels
whose full-layer alpha reaches 0.999 and the lowest alpha, and the render at the last stop beside the
photo (OUT.png), to look at.

    python alpha_at_stop.py RUN VIEW_INDEX OUT.png STOP[,STOP...]   (VIEW_INDEX: among the held-out views)
"""
import os
import sys

import drjit as dr
import numpy as np
from PIL import Image

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-12-04d"))
from common import fitted_run  # noqa: E402  (2026-12-04d's: the run and its held-out views)

from mi_voldis.metrics import psnr
from mi_voldis.render.views import render_camera

if os.path.exists(sys.argv[3]):  # a picture this script did not make is not overwritten
    sys.exit(f"error: {sys.argv[3]}: exists; choose a new file name")
run, ds, tests, res, rest = fitted_run(sys.argv[1:2])
view = tests[int(sys.argv[2])]
for stop in [float(s) for s in sys.argv[4].split(",")]:
    integ = run.integrator(occupancy_resolution=res - 1, stop_transmittance=stop, strides=True)
    with dr.suspend_grad():
        out = render_camera(integ, ds.cameras[view], ("full",))
    alpha = out["full"][1]
    img = np.clip(ds.as_photographed(out["full"]), 0, 1)
    print(f"view {view}, stop {stop:g}: alpha >= 0.999 on {np.mean(alpha >= 0.999):.4f} of the pixels, lowest "
          f"{alpha.min():.4f}; PSNR {psnr(img, ds.images[view]):.4f} dB", flush=True)
pair = np.concatenate([ds.images[view][..., :3], img[..., :3]], axis=1)
Image.fromarray(np.round(pair * 255).astype(np.uint8)).save(sys.argv[3])
