"""Loop iterations and evaluated samples a ray of a fitted run's training rays under fitting's rules (rays
stopped at transmittance 1e-4, the fitted occupancy threshold), occupancy cells of C voxels; a forward march
only, 8,192 random training pixels. Counts iterations with a probe, which the march calls once per iteration of
each ray still marching. Needs ``coarse_exit_skip.diff`` applied (``Cflat``: without the coarsened grid).

    python reports/experiments/2026-12-07b/iterations.py RUN CELLS...   (e.g. 4flat 4 2 8)
"""
import os
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

sys.path.insert(0, os.getcwd())
mi.set_variant("llvm_ad_rgb")
from mi_voldis import load_run  # noqa: E402
from mi_voldis.raybank import RayBank  # noqa: E402
from mi_voldis.render import march  # noqa: E402

RAYS = 8192

if len(sys.argv) < 3:
    sys.exit("iterations.py: give a fitted run's folder and cell sizes")
run = load_run(sys.argv[1])
ds = run.dataset
o, d, *_ = RayBank(ds, ds.train).batch(np.random.default_rng(0), RAYS)
resolution = max(run.integrator().fields["full"].shape)
for c in sys.argv[2:]:
    across = int(np.ceil((resolution - 1) / int(c.removesuffix("flat"))))
    integ = run.integrator(occupancy_resolution=across, stop_transmittance=1e-4)
    if c.endswith("flat"):
        integ.coarse_skip = lambda: ()
        integ._plans.clear()
    plan = integ.plan(("full",))
    count = dr.zeros(mi.Float, 1)

    def probe(p, w, active, depth, count=count):
        dr.scatter_reduce(dr.ReduceOp.Add, count, 1.0, mi.UInt32(0))

    fwd = march.forward(plan, march.prepare_rays(plan, o, d), dr.full(mi.Float, 0.5, RAYS), probe=probe)
    dr.eval(count, fwd.stats["evaluated"])
    print(f"cells of {c} voxels: {count[0] / RAYS:.1f} iterations a ray, "
          f"{dr.mean(fwd.stats['evaluated'])[0]:.1f} evaluated")
