"""#42: evaluated samples per ray of a fitted run at render time against the occupancy grid's cell size.

    python reports/experiments/2026-11-28/occ_cells/render_cells.py RUN VOXELS_PER_CELL[,..]

Each row renders the run's held-out views with occupancy cells VOXELS_PER_CELL voxels of the full grid
across (the fit uses 4), the run's threshold otherwise; prints PSNR, evaluated samples a ray and seconds.
"""
import importlib.util
import os
import sys
import time

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")

from mi_voldis.tasks.base import FittedRun  # noqa: E402

# one held-out view rendered with its evaluated samples: the helper of 2026-11-27's render_cost.py
_spec = importlib.util.spec_from_file_location("render_cost", os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-27", "samples", "render_cost.py"))
render_cost = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(render_cost)

run = FittedRun(sys.argv[1])
ds = run.dataset
res = max(run.fields["full"].shape)
print("run", sys.argv[1], "grid", res, "occupancy", run.properties.get("occupancy_resolution"),
      "threshold", run.properties.get("occupancy_threshold"), flush=True)


def view(integrator, v):
    return render_cost.view(integrator, ds, v)


base = None
for k in [int(a) for a in sys.argv[2].split(",")]:
    integ = run.integrator(occupancy_resolution=int(np.ceil((res - 1) / k)))
    view(integ, ds.test[0])  # compile
    t = time.perf_counter()
    out = [view(integ, v) for v in ds.test]
    sec = time.perf_counter() - t
    ev = np.concatenate([o[1] for o in out])
    imgs = [o[2] for o in out]
    diff = max(float(np.abs(a - b).max()) for a, b in zip(imgs, base)) if base else 0.0
    base = base or imgs
    print(f"cells of {k} voxels ({integ.occupancy.fraction:.3f} occupied): psnr {np.mean([o[0] for o in out]):.4f} "
          f"evaluated mean {ev.mean():.1f} p50 {np.percentile(ev, 50):.0f} p90 {np.percentile(ev, 90):.0f} "
          f"max |diff| vs first row {diff:.2e}, {sec:.1f} s for {len(ds.test)} views", flush=True)
