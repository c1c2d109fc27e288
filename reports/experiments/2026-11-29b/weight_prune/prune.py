"""#42: occupancy cells pruned by the largest weight any training ray gives a sample in them (Plenoxels'
weight pruning, applied after the fit): held-out PSNR against evaluated samples a ray.

    python reports/experiments/2026-11-29b/weight_prune/prune.py RUN TAUS [PIXEL_STRIDE] [--evaluate]
        [--prune-unsampled]

--prune-unsampled: cells no training sample falls in are pruned too (their weight counted as 0).
--evaluate: also the fit's own held-out evaluation (mi_voldis.fit.report.evaluate: the background in the
mask, coverage IoU, haze) with each pruned grid.

Each training view's rays (every PIXEL_STRIDE-th pixel along both axes) are marched through the full and
the background field; a cell keeps its occupancy when some sample in it has weight w = T alpha >= tau in
either field; a cell no training sample falls in keeps it (nothing is known of it). TAUS: comma-separated
(0: the run's occupancy as it is)."""
import importlib.util
import os
import sys
import time

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
import drjit as dr  # noqa: E402

from mi_voldis.cameras import pixel_rays  # noqa: E402
from mi_voldis.device import from_numpy  # noqa: E402
from mi_voldis.render import march  # noqa: E402
from mi_voldis.render.occupancy import Occupancy  # noqa: E402
from mi_voldis.tasks.base import FittedRun  # noqa: E402

_spec = importlib.util.spec_from_file_location("render_cost", os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-27", "samples", "render_cost.py"))
render_cost = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(render_cost)

full_eval = "--evaluate" in sys.argv
keep_unsampled = "--prune-unsampled" not in sys.argv
sys.argv = [a for a in sys.argv if a not in ("--evaluate", "--prune-unsampled")]
run = FittedRun(sys.argv[1])
ds = run.dataset
taus = [float(a) for a in sys.argv[2].split(",")]
stride = int(sys.argv[3]) if len(sys.argv) > 3 else 2
integ = run.integrator()
occ = integ.occupancy
print("run", sys.argv[1], "cells", occ.shape, f"occupied {occ.fraction:.4f}", flush=True)

t0 = time.perf_counter()
maxw = dr.full(mi.Float, -1.0, int(np.prod(occ.shape)))  # -1: no training sample in the cell
for layer in ("full", "bg"):
    plan = integ.plan((layer,))
    chain = getattr(plan.sources, layer)

    def probe(p, w, active, depth):
        u, _ = occ._cells(p)
        inside = active & dr.all((u >= 0.0) & (u < mi.Vector3f(*occ.shape)))
        i = mi.Vector3u(dr.clip(mi.Vector3i(u), 0, mi.Vector3i(*[s - 1 for s in occ.shape])))
        idx = (i.z * occ.shape[1] + i.y) * occ.shape[0] + i.x
        dr.scatter_reduce(dr.ReduceOp.Max, maxw, w[chain], idx, inside)

    for v in ds.train:
        cam = ds.cameras[v]
        py, px = np.mgrid[0:cam.height:stride, 0:cam.width:stride]
        o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
        with dr.suspend_grad():
            for s in range(0, len(o), 1 << 17):
                n = min(1 << 17, len(o) - s)
                rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o[s:s + n]), from_numpy(mi.Vector3f, d[s:s + n]))
                march.forward(plan, rays, dr.full(mi.Float, 0.5, n), probe=probe)
                dr.eval(maxw)
mw = np.array(maxw).reshape(occ.cells.shape)
print(f"max weights over {len(ds.train)} training views in {time.perf_counter() - t0:.0f} s; occupied cells' "
      f"max weight quantiles 10/50/90%: {np.percentile(mw[occ.cells], [10, 50, 90])}; "
      f"never sampled {(occ.cells & (mw < 0)).sum() / occ.cells.sum():.3f} of them", flush=True)

for tau in taus:
    cells = occ.cells & ((mw >= tau) | ((mw < 0) & keep_unsampled)) if tau > 0 else occ.cells
    pruned = Occupancy(occ.lo, occ.hi, cells, occ.reach)
    integ.use_occupancy(pruned)
    out = [render_cost.view(integ, ds, v) for v in ds.test]
    ev = np.concatenate([o[1] for o in out])
    print(f"tau {tau:g}: occupied {cells.mean():.4f} ({cells.sum() / occ.cells.sum():.3f} of the run's); psnr "
          f"{np.mean([o[0] for o in out]):.4f} ({', '.join(f'{o[0]:.2f}' for o in out)}); evaluated mean "
          f"{ev.mean():.1f} p50 {np.percentile(ev, 50):.0f} p90 {np.percentile(ev, 90):.0f}", flush=True)
    if full_eval:
        from mi_voldis.fit.report import evaluate
        summary = evaluate(ds, integ)[0]
        print("   ", {k: round(v, 4) for k, v in summary.items() if v is not None}, flush=True)
