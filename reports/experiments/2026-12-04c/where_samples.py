"""#42: where a fitted run's evaluated samples lie. Renders held-out views' pixel-centre rays of RUN's
full field (the run's own integrator: its occupancy grid and early stop) and counts every evaluated
sample by the scene-space region it lies in (contracted space: the inner cube, |p|_inf <= 1, and the
shell beyond it, in quarters of the shell's depth) and by the ray's transmittance before it (how much
of the pixel's colour the sample can still change). Prints samples a ray per bin.

    python where_samples.py RUN [VIEW ...]      (default: the first three held-out views)
"""
import sys

import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
import drjit as dr  # noqa: E402
import numpy as np  # noqa: E402

from mi_voldis.cameras import pixel_rays  # noqa: E402
from mi_voldis.device import from_numpy  # noqa: E402
from mi_voldis.render import march  # noqa: E402
from mi_voldis.tasks.base import FittedRun  # noqa: E402

T_EDGES = (1.0, 0.5, 0.1, 0.01, 1e-3)  # transmittance bins: [0.5, 1], [0.1, 0.5), ..., below 1e-3
R_BINS = 5  # inner cube, then the shell in four quarters

if len(sys.argv) < 2:
    sys.exit("usage: where_samples.py RUN [VIEW ...]")
try:
    run = FittedRun(sys.argv[1])
except (OSError, ValueError) as e:
    sys.exit(str(e))
ds = run.dataset
try:
    views = [int(v) for v in sys.argv[2:]] or list(ds.test)[:3]
except ValueError:
    sys.exit(f"views must be numbers, got {' '.join(sys.argv[2:])}")
if any(not 0 <= v < len(ds.cameras) for v in views):
    sys.exit(f"{sys.argv[1]}: views must lie in 0..{len(ds.cameras) - 1}")
integ = run.integrator()
plan = integ.plan(("full",))
space = plan.space
chain = plan.sources.full
shell = float(getattr(space, "shell", 0.0))
counts = np.zeros((R_BINS, len(T_EDGES)))
rays_total = 0
for v in views:
    cam = ds.cameras[v]
    ys, xs = np.divmod(np.arange(cam.width * cam.height), cam.width)
    o, d = pixel_rays(cam, xs + 0.5, ys + 0.5)
    for c in np.array_split(np.arange(len(o)), max(1, len(o) >> 16)):
        hist = dr.zeros(mi.Float, R_BINS * len(T_EDGES))

        def probe(p, w, active, depth):
            m = dr.max(dr.abs(p))
            r = dr.select(m <= 1.0, 0, 1 + mi.UInt32(dr.clip((m - 1.0) / max(shell, 1e-9) * 4.0, 0.0, 3.0)))
            t = dr.exp(-depth[chain])
            tb = mi.UInt32(0)
            for k, edge in enumerate(T_EDGES[1:]):
                tb += dr.select(t < edge, 1, 0)
            dr.scatter_reduce(dr.ReduceOp.Add, hist, 1.0, r * len(T_EDGES) + tb, active)

        with dr.suspend_grad():
            rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o[c]), from_numpy(mi.Vector3f, d[c]))
            march.forward(plan, rays, dr.full(mi.Float, 0.5, len(c)), probe=probe)
        counts += np.array(hist).reshape(R_BINS, len(T_EDGES))
        rays_total += len(c)
per_ray = counts / rays_total
labels = ["T in [0.5,1]", "[0.1,0.5)", "[0.01,0.1)", "[1e-3,0.01)", "< 1e-3"]
regions = ["inner cube"] + [f"shell {k}/4-{k + 1}/4" for k in range(4)]
print(f"{sys.argv[1]}: views {views}, {rays_total} rays, shell {shell:g}; evaluated samples a ray by region "
      f"(rows) and transmittance before the sample (columns)")
print("| region | " + " | ".join(labels) + " | all |")
print("|---|" + "---|" * (len(labels) + 1))
for name, row in zip(regions, per_ray):
    print(f"| {name} | " + " | ".join(f"{x:.1f}" for x in row) + f" | {row.sum():.1f} |")
print("| all | " + " | ".join(f"{x:.1f}" for x in per_ray.sum(0)) + f" | {per_ray.sum():.1f} |")
