"""Where family16's wall (fitted as a 360-degree capture with a thin contracted shell) stands, and which
training cameras could see it: median points of a held-out view's rays in front of the scene, then per point
the training cameras whose image holds it (in front of them) and its distance to the nearest training camera.

usage: python wall_trace.py RUN VIEW MAX_DEPTH [RUN_B]
RUN_B: a second run of the same dataset, whose field is probed along the same rays (its median depth there).
"""
import os
import sys

import numpy as np

import mi_voldis
from mi_voldis.cameras import DevicePoints
from mi_voldis.render.surface import _camera_rays, median_points

if len(sys.argv) not in (4, 5) or not sys.argv[2].isdigit():
    raise SystemExit(__doc__.strip().splitlines()[-2].strip())
try:
    max_depth = float(sys.argv[3])
except ValueError:
    raise SystemExit(f"wall_trace.py: MAX_DEPTH must be a number, got {sys.argv[3]!r}") from None
for path in sys.argv[1:2] + sys.argv[4:5]:
    if not os.path.isfile(os.path.join(path, "full_grid.npz")):
        raise SystemExit(f"wall_trace.py: {path}: not a run folder (no full_grid.npz)")
run, view = mi_voldis.load_run(sys.argv[1]), int(sys.argv[2])
ds = run.dataset
if view >= len(ds.cameras):
    raise SystemExit(f"wall_trace.py: VIEW {view} is out of range (the run's dataset has {len(ds.cameras)} views)")
cam = ds.cameras[view]
o, d = _camera_rays(cam)
pts, hit = median_points(run.integrator(), o, d)
depth = np.where(hit, np.linalg.norm(pts - o, axis=1), np.inf)
wall = hit & (depth < max_depth)
print(f"view {view}: {hit.mean():.3f} of rays end; {wall.mean():.3f} end nearer than {max_depth} "
      f"(median depth of the rest {np.median(depth[hit & ~wall]) if (hit & ~wall).any() else float('nan'):.2f})")
sel = np.flatnonzero(wall)[::max(1, wall.sum() // 2000)]
P = pts[sel]
at = DevicePoints(P)
seen = np.zeros(len(P), int)
for v in ds.train:
    _, ok = at.pixel_of(ds.cameras[v])
    seen += np.array(ok, dtype=int)
centres = np.array([np.asarray(ds.cameras[v].to_world)[:3, 3] for v in ds.train])
near_cam = np.linalg.norm(P[:, None, :] - centres[None], axis=2).min(axis=1)
print(f"wall points: {len(P)}; training views whose image holds them: median {np.median(seen):.0f}, "
      f"quartiles {np.percentile(seen, 25):.0f}-{np.percentile(seen, 75):.0f}, none {np.mean(seen == 0):.3f}; "
      f"distance to the nearest training camera: median {np.median(near_cam):.2f} "
      f"({np.percentile(near_cam, 10):.2f}-{np.percentile(near_cam, 90):.2f}); "
      f"camera ring radius about {np.median(np.linalg.norm(centres - centres.mean(0), axis=1)):.2f}")
space = run.integrator().plan(("full",)).space
local = space.from_world_np(P)
if local is not None:
    r = np.abs(local).max(axis=1)
    print(f"wall points in the box's frame: max-norm median {np.median(r):.3f} (linear cube <= 1)")
if len(sys.argv) > 4:
    other = mi_voldis.load_run(sys.argv[4])
    p2, h2 = median_points(other.integrator(), o[sel], d[sel])
    d2 = np.where(h2, np.linalg.norm(p2 - o[sel], axis=1), np.inf)
    print(f"{sys.argv[4]} on the same rays: median depth {np.median(d2):.2f}, "
          f"nearer than {max_depth}: {np.mean(d2 < max_depth):.3f}")
