"""The kernels of mi.render's adjoint (the voldis integrator's ``render_backward``): one render of a 6x6
orthographic view (12 samples, random 4^3 fields, 2 spp) and its backward, with Dr.Jit's kernel history on.
Prints how many kernels hold the primal's loop, the adjoint's, and both, and the adjoint kernel's operations.

    PYTHONPATH=CHECKOUT python render_adjoint_kernels.py"""
import os
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
import mi_voldis  # noqa: E402,F401  (registers the plugins)
from mi_voldis.render import march  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(march.__file__), "..", "..", "tests"))
from helpers import ortho_scene, random_field  # noqa: E402

scene = ortho_scene({"type": "voldis", "samples": 12, "full": random_field(3), "bg": random_field(4)}, size=6, spp=2)
params = mi.traverse(scene)
dr.enable_grad(params["integrator.full.density"])
params.update()
dr.set_flag(dr.JitFlag.KernelHistory, True)
dr.kernel_history()  # clears it
image = mi.render(scene, params, seed=1)
dr.backward(dr.sum(image.array * mi.Float(np.random.default_rng(2).normal(size=dr.width(image.array)))))
grad = np.array(dr.grad(params["integrator.full.density"]))
kernels = [(e["ir"].getvalue() if hasattr(e["ir"], "getvalue") else str(e["ir"]), e.get("operation_count"))
           for e in dr.kernel_history() if e.get("ir") is not None]
primal = sum("voldis primal" in ir for ir, _ in kernels)
adjoint = [n for ir, n in kernels if "voldis adjoint" in ir]
both = sum("voldis primal" in ir and "voldis adjoint" in ir for ir, _ in kernels)
print(f"{march.__file__}: kernels with the primal's loop {primal}, with the adjoint's {len(adjoint)}, with both "
      f"{both}; adjoint kernel operations {adjoint}; largest gradient {np.abs(grad).max():.6g}")
