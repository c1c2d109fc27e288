"""#46: where the background's weight lies along the rays through the removed object, against the full
field's on the rays beside it (the statue's column).

    python reports/experiments/2026-11-28/statue_column/weights.py RUN VIEW [BIN_EDGES]

Prints, per distance bin (world units from the camera), the mean weight per ray of the 'bg' layer on the
rays inside the view's mask (dilated by the fit's hull_dilation) and of 'bg' and 'full' on a ring just outside it.
"""
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
import drjit as dr  # noqa: E402

from mi_voldis.device import from_numpy  # noqa: E402
from mi_voldis.metrics import dilate  # noqa: E402
from mi_voldis.render import march  # noqa: E402
from mi_voldis.render.surface import _camera_rays  # noqa: E402
from mi_voldis.tasks.base import FittedRun  # noqa: E402

run = FittedRun(sys.argv[1])
view = int(sys.argv[2])
edges = np.array([float(a) for a in sys.argv[3].split(",")]) if len(sys.argv) > 3 else \
    np.array([0, 30, 36, 42, 50, 60, 80, 110, 150, 250, 500, 1e3, 1e4, 1e9])
ds, integ = run.dataset, run.integrator()
cam = ds.cameras[view]
o, d = _camera_rays(cam)
diag = np.hypot(*ds.size)
mask = dilate(ds.masks[view], int(np.ceil(0.03 * diag))).ravel()
ring = dilate(ds.masks[view], int(np.ceil(0.08 * diag))).ravel() & ~mask


def binned(layer, pick):
    plan = integ.plan((layer,))
    chain = getattr(plan.sources, layer)
    oo, dd = o[pick], d[pick]
    n = len(oo)
    hist = dr.zeros(mi.Float, n * len(edges))
    index = dr.arange(mi.UInt32, n)
    origin = from_numpy(mi.Point3f, oo)
    with dr.suspend_grad():
        def probe(p, w, active, _depth):
            t = dr.norm(plan.space.to_world(p) - origin)
            b = mi.UInt32(0)
            for e in edges[1:]:
                b += mi.UInt32(dr.select(t >= float(e), 1, 0))
            dr.scatter_reduce(dr.ReduceOp.Add, hist, w[chain], index * len(edges) + b, active)
        rays = march.prepare_rays(plan, origin, from_numpy(mi.Vector3f, dd))
        march.forward(plan, rays, dr.full(mi.Float, 0.5, n), probe=probe)
    return np.array(hist).reshape(n, len(edges))[:, :-1].mean(axis=0)


rows = {"bg in mask": binned("bg", mask), "bg on ring": binned("bg", ring), "full on ring": binned("full", ring),
        "full in mask": binned("full", mask)}
print(f"view {view}: {mask.sum()} rays in the dilated mask, {ring.sum()} on the ring")
print("bin".ljust(14) + "".join(k.rjust(14) for k in rows))
for i in range(len(edges) - 1):
    print(f"{edges[i]:g}-{edges[i + 1]:g}".ljust(14) + "".join(f"{v[i]:14.3f}" for v in rows.values()))
print("total".ljust(14) + "".join(f"{v.sum():14.3f}" for v in rows.values()))
