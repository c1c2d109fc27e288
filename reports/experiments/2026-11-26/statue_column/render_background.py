"""The background layer of held-out view V and its alpha, side by side, as one PNG."""

import sys

import numpy as np
from kept_run import run_integrator

from mi_voldis.io.images import display_to_uint8, write_png
from mi_voldis.render.views import render_camera

run, v, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
ds, integ = run_integrator(run)
r = render_camera(integ, ds.cameras[v], ("bg",))["bg"]
rgb, a = r[0], r[1]
img = np.concatenate([np.clip(rgb, 0, 1), np.repeat(a[..., None], 3, -1)], 1)
write_png(out, display_to_uint8(img))
