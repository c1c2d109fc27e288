"""#46 item 3: what the statue's hull fill starts from. The refill region's boundary (stored vertices outside it
with a neighbour in it), split into hull vertices kept as seen and vertices outside the hull, and by distance to
the object's voxels; their density as opacity per voxel; and the filled region's, before any refit.

    python fill_boundary.py RUN      # RUN: a fit kept with --keep-checkpoints
"""
# ruff: noqa: E402, E741
import os
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

import mi_voldis  # noqa: F401  (sets the variant)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from probe_run import load_run  # noqa: E402

from mi_voldis.activations import softplus
from mi_voldis.field_state import dilate_vertices, neighbour_vertices
from mi_voldis.fit.background import background_regions, fill_weights, harmonic_fill, voxel_of

run = sys.argv[1]
cfg, ds, state, inputs = load_run(run)
full = state.fields["full"]
nb = neighbour_vertices(full)
hull, points, obj, refill = background_regions(inputs, state, nb)
region = refill & (hull > 0)
voxel = voxel_of(full)


def alpha(raw):
    sigma = np.array(softplus(mi.Float(raw))) * full.density_scale
    return 1.0 - np.exp(-sigma * voxel)


raw = np.array(dr.gather(mi.Float, full.data, dr.arange(mi.UInt32, full.vertices) * full.width))
R, H, O = np.array(region), np.array(hull) > 0, np.array(obj)
weights = fill_weights(inputs, full, points)
print("fill weights (-x, +x, -y, +y, -z, +z):", [round(float(w), 3) for w in weights])
# the boundary the fill reads: vertices outside the region that a region vertex has as a neighbour along a
# direction of weight above 0.1
boundary = np.zeros(full.vertices, bool)
idx = np.flatnonzero(R)
for k, n in enumerate(nb):
    if float(weights[k]) > 0.1:
        other = np.array(n)[idx]
        boundary[other[~R[other]]] = True
near_obj = np.array(dilate_vertices(obj, nb, 4))
print(f"region {R.sum()}, object {O.sum()}, boundary {boundary.sum()}")
for name, sel in (("boundary, kept hull", boundary & H), ("boundary, outside hull", boundary & ~H),
                  ("boundary within 4 of the object", boundary & near_obj),
                  ("boundary farther from the object", boundary & ~near_obj)):
    a = alpha(raw[sel])
    if len(a):
        print(f"{name}: {sel.sum()} vertices, opacity a voxel mean {a.mean():.4f}, median {np.median(a):.4f}, "
              f"p90 {np.percentile(a, 90):.4f}, above 0.05: {(a > 0.05).mean():.3f}")
values = np.array(harmonic_fill(full.bricks_data(), full.width, dr.select(region, 1.0, 0.0), nb, weights=weights))
filled = values.reshape(-1, full.width)[:full.vertices, 0] if values.size >= full.vertices * full.width else None
if filled is not None:
    a = alpha(filled[R & ~O])
    print(f"filled region (object excluded): opacity a voxel mean {a.mean():.4f}, median {np.median(a):.4f}, "
          f"p90 {np.percentile(a, 90):.4f}")
    a = alpha(raw[R & ~O])
    print(f"the same vertices in the full field: mean {a.mean():.4f}, median {np.median(a):.4f}")

# where the dense boundary lies: world distance from the cameras' centroid and height along the up
from mi_voldis.cameras import world_up  # noqa: E402
from mi_voldis.field_state import vertex_positions  # noqa: E402

pts, real = vertex_positions(full)
world = inputs.space.to_world_np(pts)
cams = np.stack([np.asarray(ds.cameras[i].to_world)[:3, 3] for i in ds.train]).mean(0)
up = world_up([ds.cameras[i] for i in ds.train])
centre = np.median(world[np.array(obj)], 0)
print(f"object's median point {centre.round(2)}, {np.linalg.norm(centre - cams):.1f} from the cameras' centroid")
for name, sel in (("outside-hull boundary, opacity > 0.2", boundary & ~H & (alpha(raw) > 0.2)),
                  ("kept boundary, opacity > 0.2", boundary & H & (alpha(raw) > 0.2)),
                  ("kept boundary, opacity < 0.05", boundary & H & (alpha(raw) < 0.05))):
    w = world[sel]
    dist = np.linalg.norm(w - cams, axis=1)
    height = (w - centre) @ up
    print(f"{name}: {sel.sum()}; distance p10/50/90 {np.percentile(dist, [10, 50, 90]).round(1)}, "
          f"height above the object's median p10/50/90 {np.percentile(height, [10, 50, 90]).round(2)}")
