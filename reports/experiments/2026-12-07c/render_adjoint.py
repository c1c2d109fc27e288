"""mi.render's adjoint (the voldis integrator's ``render_backward``), timed: one render and its backward on a
random 64^3 full and background field, 128 samples a ray, a 128x128 orthographic view at 4 spp. Run it from two
checkouts in alternation, so both see the same load:

    for r in 1 2 3; do for c in OLD NEW; do PYTHONPATH=$c python render_adjoint.py; done; done

Prints the checkout's march module and the median of 5 render-and-backward rounds after one warm-up."""
import os
import sys
import time

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
import mi_voldis  # noqa: E402,F401  (registers the plugins)
from mi_voldis.render import march  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(march.__file__), "..", "..", "tests"))
from helpers import ortho_scene, random_field  # noqa: E402

scene = ortho_scene({"type": "voldis", "samples": 128, "full": random_field(3, (64, 64, 64)),
                     "bg": random_field(4, (64, 64, 64))}, size=128, spp=4)
params = mi.traverse(scene)
dr.enable_grad(params["integrator.full.density"])
params.update()
times = []
for k in range(6):
    dr.set_grad(params["integrator.full.density"], 0.0)
    t = time.perf_counter()
    image = mi.render(scene, params, seed=k)
    weights = mi.Float(np.random.default_rng(2).normal(size=dr.width(image.array)).astype(np.float32))
    dr.backward(dr.sum(image.array * weights))
    dr.eval(dr.grad(params["integrator.full.density"]))
    dr.sync_thread()
    times.append(time.perf_counter() - t)
print(f"{march.__file__}: {np.median(times[1:]) * 1e3:.1f} ms a render and backward (median of 5)")
