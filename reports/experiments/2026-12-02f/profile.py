"""#46 probe: the full field's and the background's density by height, through the object's footprint and
on a ring around it (12 vertices out, a 4-vertex gap), from a finished run's two grids. The object's vertices
are those dense in the full field (raw density > -1.5) and emptied in the background (< -5); the grid's
second axis is the world's up on the family's rigs. Columns: mean per-voxel optical depth softplus(raw)
(opacity 1 - exp(-that) per voxel) in the footprint (full, background), on the ring (full, background), and
the share of the footprint's vertices at that height that are the object's.

    python profile.py RUN
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 3)))

from mi_voldis.bricks import Layout  # noqa: E402

if len(sys.argv) != 2:
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
run = sys.argv[1]
for name in ("full_grid.npz", "bg_grid.npz"):
    if not os.path.isfile(os.path.join(run, name)):
        raise SystemExit(f"profile.py: {run}: not a finished run (no {name})")
zf, zb = np.load(os.path.join(run, "full_grid.npz")), np.load(os.path.join(run, "bg_grid.npz"))
lay = Layout(tuple(zf["vertices"]), int(zf["brick"]), zf["table"])
coords, inside = lay.vertex_coords()
if len(coords) == len(zf["data"]) + lay.vertices_per_brick:  # the file leaves out the empty slot
    coords, inside = coords[lay.vertices_per_brick:], inside[lay.vertices_per_brick:]
df, db = zf["data"][:, 0], zb["data"][:, 0]
obj = inside & (df > -1.5) & (db < -5)
if not obj.any():
    raise SystemExit(f"profile.py: {run}: no vertex dense in the full field and emptied in the background")
c = coords[obj]
print(f"object vertices {obj.sum()}, from {c.min(0).tolist()} to {c.max(0).tolist()}; scene box {zf['bbox'].tolist()}")
(x0, _, z0), (x1, _, z1) = c.min(0), c.max(0)
x, z = coords[:, 0], coords[:, 2]
foot = inside & (x >= x0) & (x <= x1) & (z >= z0) & (z <= z1)
near = (x >= x0 - 4) & (x <= x1 + 4) & (z >= z0 - 4) & (z <= z1 + 4)
ring = inside & (x >= x0 - 12) & (x <= x1 + 12) & (z >= z0 - 12) & (z <= z1 + 12) & ~near
tau = np.logaddexp(0, df), np.logaddexp(0, db)
print("  y  full_foot  bg_foot  full_ring  bg_ring  object")
for y in range(int(coords[inside, 1].min()), int(c[:, 1].max()) + 6):
    f, r = foot & (coords[:, 1] == y), ring & (coords[:, 1] == y)
    if f.any() and r.any():
        print(f"{y:3d}  {tau[0][f].mean():9.4f} {tau[1][f].mean():8.4f} {tau[0][r].mean():10.4f} "
              f"{tau[1][r].mean():8.4f}  {obj[f].mean():6.2f}")
