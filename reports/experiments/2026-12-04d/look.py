"""Photo, render without strides, with them, and |difference| x 10 of one held-out view of a fitted run, written
to PNG (refused if it exists).

    python look.py RUN INDEX PNG   (INDEX into the held-out views)
"""
import os
import sys

import drjit as dr
import numpy as np
from common import fitted_run

from mi_voldis.io.images import write_png
from mi_voldis.render.views import render_camera

run, ds, views, res, (index, png) = fitted_run(sys.argv[1:])
if os.path.exists(png):
    sys.exit(f"error: {png} exists; give a new file")
v = views[int(index)]
imgs = []
for strides in (False, True):
    integ = run.integrator(occupancy_resolution=res - 1, stop_transmittance=1e-3, strides=strides)
    with dr.suspend_grad():
        imgs.append(np.clip(ds.as_photographed(render_camera(integ, ds.cameras[v], ("full",))["full"]), 0, 1))
diff = np.clip(np.abs(imgs[1] - imgs[0]) * 10, 0, 1)
write_png(png, (np.concatenate([ds.images[v], imgs[0], imgs[1], diff], axis=1) * 255).round().astype(np.uint8))
print(f"largest difference {np.abs(imgs[1] - imgs[0]).max():.4f}")
