"""#46: the hull vertices seen only through the object's dark fringe (unseen when the fringe counts as masked,
seen otherwise), what the full field holds there and what the hull fill would put there: opacity a voxel,
luminance, and where they stand against the full field's surface on the fringe's own rays.

    python probe.py RUN      # RUN: a fit kept with --keep-checkpoints (reads the 2026-11-30b probe_run)
"""
# ruff: noqa: E402
import dataclasses
import os
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

import mi_voldis  # noqa: F401  (sets the variant)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.activations import softplus
from mi_voldis.cameras import pixel_of
from mi_voldis.field_state import neighbour_vertices, vertex_positions
from mi_voldis.fit.background import fill_weights, harmonic_fill, hull_region, never_seen, voxel_of
from mi_voldis.fit.fringe import find_fringe
from mi_voldis.fit.lift import training_depths

run = sys.argv[1]
cfg, ds, state, inputs = load_run(run)
full = state.fields["full"]
nb = neighbour_vertices(full)
depth = training_depths(inputs, state, median=True)
fringe = find_fringe(ds, cfg.fringe_width, cfg.fringe_contrast, depth)
on = dataclasses.replace(inputs, fringe=fringe, cfg=dataclasses.replace(cfg, fringe_unseen=True))
hull, points = hull_region(inputs, full, nb, depth)
H = np.array(hull) > 0
strict = np.array(never_seen(inputs, full, hull > 0, depth))
loose = np.array(never_seen(on, full, hull > 0, depth))
F = loose & ~strict
voxel = voxel_of(full)
data = np.array(full.bricks_data()).reshape(-1, full.width)


def alpha(raw):
    return 1.0 - np.exp(-np.array(softplus(mi.Float(raw))) * full.density_scale * voxel)


weights = fill_weights(inputs, full, points)
filled = np.array(harmonic_fill(full.bricks_data(), full.width, dr.select(mi.Bool(loose), hull, 0.0), nb,
                                weights=weights)).reshape(-1, full.width)
print(f"{os.path.basename(run.rstrip('/'))}: hull {H.sum()}, strict unseen {strict.sum()}, fringe-only {F.sum()}, "
      f"fringe {int(fringe.sum())} px in {int(fringe.any(axis=(1, 2)).sum())} views")
af, ai = alpha(data[:full.vertices, 0]), alpha(filled[:full.vertices, 0])
lum = lambda d: d[:full.vertices, 1:4].mean(1)  # noqa: E731  (raw colour coefficients, degree 0 first)
for name, sel in (("fringe-only", F), ("strict unseen", strict & H), ("seen hull", H & ~loose)):
    if sel.any():
        up, down = (ai[sel] > af[sel] + .05).mean(), (ai[sel] < af[sel] - .05).mean()
        print(f"  {name}: opacity full mean {af[sel].mean():.3f} median {np.median(af[sel]):.3f} | fill mean "
              f"{ai[sel].mean():.3f} median {np.median(ai[sel]):.3f} | fill - full: up {up:.2f}"
              f" down {down:.2f} | colour raw full {lum(data)[sel].mean():+.3f} fill "
              f"{lum(filled)[sel].mean():+.3f}")
# where the fringe-only vertices stand on the fringe's rays: distance along the ray over the full field's depth
pts, real = vertex_positions(full)
world = inputs.space.to_world_np(pts[F])
ratios = []
for v in depth:
    if v not in set(int(u) for u in ds.masked_train) or not fringe[v].any():
        continue
    cam = ds.cameras[v]
    ix, iy, ok = pixel_of(cam, world)
    hit = np.zeros(len(world), bool)
    hit[ok] = fringe[v][iy[ok], ix[ok]]
    dist = np.linalg.norm(world[hit] - np.asarray(cam.to_world)[:3, 3], axis=1)
    ratios.append(dist / depth[v][iy[hit], ix[hit]])
r = np.concatenate(ratios) if ratios else np.array([])
if len(r):
    print("  fringe-only vertices on fringe rays, distance / full-field depth: "
          + " ".join(f"p{q} {np.percentile(r, q):.3f}" for q in (5, 25, 50, 75, 95)))
