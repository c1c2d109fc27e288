"""#46: what the full field holds in and around the object's visual hull, by class and by place: outside the hull
(by rings out from it), the kept hull vertices (some training view sees them unmasked), the refilled (unseen)
ones and the object's voxels, binned by height above the floor (the world's up from the cameras) and by steps
(vertex rings) in from the hull's outside. On a capture whose hull runs out to a contracted space's far shell
(the statue's) the height bands are meaningless: the object's top then lies at 1e12 world units. Opacity a
voxel, colour sigmoid(C_0) (degree 0), and the count.

    python probe.py RUN [KEY=VALUE ...]   # RUN: a fit kept with --keep-checkpoints (reads the 2026-11-30b
                                          # probe_run), under today's background settings and these
"""
# ruff: noqa: E402
import os
import sys

import mitsuba as mi
import numpy as np

import mi_voldis  # noqa: F401  (sets the variant)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.activations import softplus
from mi_voldis.cameras import world_up
from mi_voldis.field_state import dilate_vertices, neighbour_vertices, vertex_positions
from mi_voldis.fit.background import background_regions, voxel_of
from mi_voldis.fit.fringe import find_fringe
from mi_voldis.fit.lift import training_depths

run = sys.argv[1]
cfg, ds, state, inputs = load_run(run)
if sys.argv[2:]:
    from mi_voldis.fit.fields import FitInputs
    cfg = cfg.replace(**{k: type(getattr(cfg, k))(v) for k, v in (a.split("=", 1) for a in sys.argv[2:])})
    inputs = FitInputs.of(ds, cfg, os.devnull, progress=False)
full = state.fields["full"]
nb = neighbour_vertices(full)
depths = {}
depth = training_depths(inputs, state, median=True, memo=depths)
if cfg.fringe_contrast > 0:
    import dataclasses
    inputs = dataclasses.replace(inputs, fringe=find_fringe(ds, cfg.fringe_width, cfg.fringe_contrast, depth))
hull, points, obj, refill = background_regions(inputs, state, nb, depths=depths)
H, OBJ, R = np.array(hull) > 0, np.array(obj), np.array(refill)
voxel = voxel_of(full)
data = np.array(full.bricks_data()).reshape(-1, full.width)[:full.vertices]
alpha = 1.0 - np.exp(-np.array(softplus(mi.Float(data[:, 0]))) * full.density_scale * voxel)
rgb = 1 / (1 + np.exp(-data[:, 1:4]))
# rings in from the hull's outside: how many dilations of the outside reach a vertex
outside = mi.Bool(~H)
ring = np.full(full.vertices, 99)
ring[~H] = 0
grown = outside
for k in range(1, 12):
    grown = dilate_vertices(grown, nb, 1)
    g = np.array(grown)
    ring[g & (ring == 99)] = k
# rings out from the hull: -k for the vertices k dilations of the hull reach
grown = mi.Bool(H)
for k in range(1, 9):
    grown = dilate_vertices(grown, nb, 1)
    g = np.array(grown)
    ring[g & (ring == 0)] = -k
ring[ring == 0] = -99
pts, real = vertex_positions(full)
world = inputs.space.to_world_np(pts)
up = world_up([ds.cameras[i] for i in ds.train])
height = world @ up
floor = np.percentile(height[H & (alpha > 0.5)], 5) if (H & (alpha > 0.5)).any() else height[H].min()
top = height[OBJ].max() if OBJ.any() else height[H].max()
print(f"{os.path.basename(run.rstrip('/'))}: hull {H.sum()}, object {OBJ.sum()}, refilled {(R & ~OBJ).sum()}, kept "
      f"{(H & ~R).sum()}; floor at {floor:.3f}, object top {top:.3f}, voxel {voxel:.4f}")
bands = np.linspace(floor - 0.02 * (top - floor), top + 0.1 * (top - floor), 7)
for name, sel, rings in (("outside", ~H, ((-8, -7), (-6, -5), (-4, -3), (-2, -2), (-1, -1))),
                         ("kept", H & ~R, None), ("refilled", R & ~OBJ, None), ("object", OBJ, None)):
    print(f"  {name}: rows = height band above the floor (object's height 1), columns = "
          + ("rings out from the hull 8-7, 6-5, 4-3, 2, 1" if rings else "rings in from the hull's outside 1..6, 7+")
          + ": opacity a voxel / colour / count")
    for lo, hi in zip(bands[:-1], bands[1:]):
        cells = []
        for r0, r1 in rings or ((1, 1), (2, 2), (3, 3), (4, 4), (5, 5), (6, 6), (7, 99)):
            s = sel & real & (height >= lo) & (height < hi) & (ring >= r0) & (ring <= r1)
            cells.append(f"{alpha[s].mean():.3f}/{rgb[s].mean():.2f}/{s.sum()}" if s.any() else "-")
        print(f"    {(lo - floor) / (top - floor):+.2f}..{(hi - floor) / (top - floor):+.2f}: " + "  ".join(cells))
