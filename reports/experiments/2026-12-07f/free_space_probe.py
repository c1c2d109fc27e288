"""#46 probe: clear the full field's density in the free space the masks prove: for each masked training view, the
stored vertices outside the visual hull that project inside its (eroded) mask nearer than the hull's nearest
vertex on that pixel: on a masked ray nothing but the object stands before the object. Writes a run copy OUT
(config.json, checkpoints/last.npz with the cleared full field) for `bench.strategies OUT guided ...`, and prints
the held-out PSNR of the full field before / after (each view's render against its photo in DATA/images).

    python free_space_probe.py RUN DATA OUT [MARGIN]
"""
import os
import shutil
import sys

import mitsuba as mi
import numpy as np
from PIL import Image

import mi_voldis  # noqa

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.field.state import vertex_positions
from mi_voldis.fit.fields import fit_integrator
from mi_voldis.fit.free_space import free_vertices
from mi_voldis.metrics import diagonal_pixels
from mi_voldis.render.views import render_camera

if len(sys.argv) < 4:
    raise SystemExit("usage: python free_space_probe.py RUN DATA OUT [MARGIN]")
run, data, out = sys.argv[1], sys.argv[2], sys.argv[3]
margin = float(sys.argv[4]) if len(sys.argv) > 4 else 0.02
if os.path.exists(out):
    raise SystemExit(f"error: {out} exists")
cfg, ds, state, inputs = load_run(run, data)
full = state.fields["full"]
_, real = vertex_positions(full)
views = list(ds.masked_train)  # every masked training view marks it (the package takes 24 spread over them)
cleared = free_vertices(full, inputs.space, [ds.cameras[v] for v in views], ds.masks[views],
                        diagonal_pixels(cfg.hull_dilation, ds.size), cfg.hull_min_views, margin)
print("free vertices cleared", int(cleared.sum()), "of", int(real.sum()), flush=True)
integ = fit_integrator(inputs, state)
def heldout(integ):
    vals = []
    for v in ds.test:
        rgb = render_camera(integ, ds.cameras[v], ("full",))["full"][0]
        png = np.asarray(Image.open(os.path.join(data, "images", f"view_{v:03d}.png")).convert("RGB"), float) / 255
        vals.append(-10 * np.log10(np.mean((np.clip(rgb, 0, 1) - png) ** 2)))
    return vals
before = heldout(integ)
arr = np.array(full.bricks_data()).reshape(-1, full.width)
arr[cleared, 0] = -20.0
state.fields["full"] = full.with_bricks(mi.Float(arr.ravel()))
after = heldout(fit_integrator(inputs, state))
print("held-out full PSNR per view before", np.round(before, 2), "after", np.round(after, 2))
os.makedirs(os.path.join(out, "checkpoints"))
shutil.copy(os.path.join(run, "config.json"), out)
state.save(os.path.join(out, "checkpoints", "last.npz"), "bg", 0)
