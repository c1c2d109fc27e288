"""#42: how many loop iterations a ray's march takes against the samples it evaluates (occupied, before
termination), on a fitted run's held-out views through the full field. A symbolic loop masks a probe's side
effects by its own condition, so a scatter-add of 1 per call counts each ray's iterations.

    python reports/experiments/2026-11-29b/march_iterations/iterations.py RUN
"""
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
import drjit as dr  # noqa: E402

from mi_voldis.cameras import pixel_rays  # noqa: E402
from mi_voldis.device import from_numpy  # noqa: E402
from mi_voldis.render import march  # noqa: E402
from mi_voldis.tasks.base import FittedRun  # noqa: E402

run = FittedRun(sys.argv[1])
ds = run.dataset
integ = run.integrator()
plan = integ.plan(("full",))
its, evs = [], []
for v in ds.test:
    cam = ds.cameras[v]
    py, px = np.mgrid[0:cam.height, 0:cam.width]
    o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
    for s in range(0, len(o), 1 << 16):
        n = min(1 << 16, len(o) - s)
        count, evaluated = dr.zeros(mi.Float, n), dr.zeros(mi.Float, n)
        index = dr.arange(mi.UInt32, n)

        def probe(p, w, active, depth):
            dr.scatter_add(count, 1.0, index)
            dr.scatter_add(evaluated, 1.0, index, active)

        with dr.suspend_grad():
            rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o[s:s + n]), from_numpy(mi.Vector3f, d[s:s + n]))
            march.forward(plan, rays, dr.full(mi.Float, 0.5, n), probe=probe)
        its.append(np.array(count))
        evs.append(np.array(evaluated))
its, evs = np.concatenate(its), np.concatenate(evs)
print(f"{sys.argv[1]}: iterations a ray mean {its.mean():.1f} (p50 "
      f"{np.percentile(its, 50):.0f}, p90 {np.percentile(its, 90):.0f}); evaluated samples mean {evs.mean():.1f}; "
      f"iterations without a lookup {1 - evs.sum() / its.sum():.2f} of all")
