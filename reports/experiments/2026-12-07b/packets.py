"""Loop iterations per ray of 8,192 random training rays of a fitted run (fitting's rules: cells of 4 voxels, rays
stopped at transmittance 1e-4), counted by a probe that the march calls once per iteration of each ray still
marching; and the mean over SIMD packets of their longest ray, the rays in drawn order and sorted by iterations.

    python reports/experiments/2026-12-07b/packets.py RUN
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

if len(sys.argv) < 2:
    sys.exit("packets.py: give a fitted run's folder")
run = load_run(sys.argv[1])
ds = run.dataset
o, d, *_ = RayBank(ds, ds.train).batch(np.random.default_rng(0), RAYS)
resolution = max(run.integrator().fields["full"].shape)
integ = run.integrator(occupancy_resolution=int(np.ceil((resolution - 1) / 4)), stop_transmittance=1e-4)
plan = integ.plan(("full",))
count = dr.zeros(mi.Float, RAYS)


def probe(p, w, active, depth):
    dr.scatter_reduce(dr.ReduceOp.Add, count, 1.0, dr.arange(mi.UInt32, RAYS))


march.forward(plan, march.prepare_rays(plan, o, d), dr.full(mi.Float, 0.5, RAYS), probe=probe)
it = np.array(count)
print(f"iterations a ray: mean {it.mean():.1f}, median {np.median(it):.0f}, 90th percentile "
      f"{np.percentile(it, 90):.0f}, 99th {np.percentile(it, 99):.0f}, max {it.max():.0f}")
for width in (8, 16):
    drawn = it.reshape(-1, width).max(1).mean()
    ordered = np.sort(it).reshape(-1, width).max(1).mean()
    print(f"packets of {width}: longest ray {drawn:.1f} on average as drawn ({drawn / it.mean():.2f} x the mean), "
          f"{ordered:.1f} sorted ({ordered / it.mean():.2f} x)")
