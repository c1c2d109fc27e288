"""#46 probe: which of a mask's gaps a fitted full field calls an occluder's (its ray gathers an opacity of 1/4
before the hull: red) and which a notch (green), in views 1, 11 and 20 of a run (its final field), beside
the photographs; and the free vertices on its final lattice with the masks' gaps alone and with the gaps the
field tells (5bbba03's rule on the same run: ../2026-12-07g/compare_rules.py).

    python gap_kinds.py RUN DATA SHEET.png
"""
import os
import sys

import numpy as np
from PIL import Image

import mi_voldis  # noqa

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.cameras import DevicePoints
from mi_voldis.data.types import spread
from mi_voldis.field.state import vertex_positions
from mi_voldis.fit import free_space as today
from mi_voldis.fit.fields import fit_integrator
from mi_voldis.fit.hull import visual_hull
from mi_voldis.metrics import diagonal_pixels

run, data, sheet = sys.argv[1], sys.argv[2], sys.argv[3]
if os.path.exists(sheet):
    raise SystemExit(f"error: {sheet} exists")
cfg, ds, state, inputs = load_run(run, data)
full = state.fields["full"]
views = [ds.masked_train[k] for k in spread(len(ds.masked_train), today.VIEWS)]
dilation = diagonal_pixels(cfg.hull_dilation, ds.size)
args = ([ds.cameras[v] for v in views], ds.masks[views], dilation, cfg.hull_min_views, cfg.free_space_margin)
depth = today.field_gap_depth(fit_integrator(inputs, state))
alone = today.free_vertices(full, inputs.space, *args)
told = today.free_vertices(full, inputs.space, *args, depth)
print(f"free vertices: gaps alone {int(alone.sum())}, told {int(told.sum())}")
# the gaps of three views as free_vertices makes them, and the field's call on each
pts, real = vertex_positions(full)
world = inputs.space.to_world_np(pts[real])
hull = visual_hull(world, args[0], args[1], dilation, cfg.hull_min_views)
tiles = []
for v in (1, 11, 20):
    cam, mask = ds.cameras[v], ds.masks[v]
    shell = DevicePoints(world[hull])
    index, ok = (np.array(a) for a in shell.pixel_of(cam))
    ok = ok.astype(bool)
    dist = np.array(shell.distance(cam))[ok]
    near = np.full(mask.size, np.inf)
    np.minimum.at(near, index[ok], dist)
    angle = np.radians(cam.fov_x) / cam.width
    voxel = float(np.max(np.diag(full.to_world)[:3] / (np.array(full.shape) - 1)))
    edge = today.voxel_world(inputs.space, world[hull][ok], voxel)
    radius = int(np.ceil(edge / (angle * float(np.median(dist))))) + 1
    ahead = today.nearest_filter(near.reshape(mask.shape), radius)
    gaps = today.mask_gaps(mask, today.GAP_VOXELS * radius)
    at = np.flatnonzero(gaps)
    hull_at = ahead.reshape(-1)[at]
    hull_at = np.where(np.isfinite(hull_at), hull_at, dist.min())
    front = depth(cam, at) < hull_at
    vis = np.zeros(mask.shape + (3,), np.uint8)
    vis[mask] = 255
    vis.reshape(-1, 3)[at[front]] = (255, 0, 0)
    vis.reshape(-1, 3)[at[~front]] = (0, 200, 0)
    print(f"view {v}: {len(at)} gap pixels, {int(front.sum())} an occluder's")
    tiles += [Image.open(os.path.join(data, "images", f"view_{v:03d}.png")).convert("RGB"), Image.fromarray(vis)]
w, h = tiles[0].size
out = Image.new("RGB", (len(tiles) * w, h))
for k, t in enumerate(tiles):
    out.paste(t, (k * w, 0))
out.save(sheet)
