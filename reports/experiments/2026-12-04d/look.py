"""Photo, render without strides, with them, and |difference| x 10 of one held-out view of a fitted run.

    python look.py RUN INDEX PNG   (INDEX into the held-out views)
"""
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
import drjit as dr  # noqa: E402

from mi_voldis.io.images import write_png  # noqa: E402
from mi_voldis.render.views import render_camera  # noqa: E402
from mi_voldis.tasks.base import FittedRun  # noqa: E402

run = FittedRun(sys.argv[1])
ds = run.dataset
v = ds.test[int(sys.argv[2])]
res = max(run.fields["full"].shape)
imgs = []
for strides in (False, True):
    integ = run.integrator(occupancy_resolution=res - 1, stop_transmittance=1e-3, strides=strides)
    with dr.suspend_grad():
        imgs.append(np.clip(ds.as_photographed(render_camera(integ, ds.cameras[v], ("full",))["full"]), 0, 1))
diff = np.clip(np.abs(imgs[1] - imgs[0]) * 10, 0, 1)
write_png(sys.argv[3], (np.concatenate([ds.images[v], imgs[0], imgs[1], diff], axis=1) * 255).round().astype(np.uint8))
print(f"largest difference {np.abs(imgs[1] - imgs[0]).max():.4f}")
