"""#46 probe: does the masks' free space take an occluder? For a family run, the stored vertices that
`free_vertices` marks (the package's 24 spread masked views, the run's settings), how many of them lie within R
of the occluder box of the dataset's scene (DATA/scene/scene.xml's `occluder`) against how many vertices lie
there at all, and their heights; with PER_VIEW=1 also which view alone marks them (the other 23 leave them).

    [PER_VIEW=1] python free_near_pole.py RUN DATA [R]
"""
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np

import mi_voldis  # noqa

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.data.types import spread
from mi_voldis.field.state import vertex_positions
from mi_voldis.fit.free_space import VIEWS, free_vertices
from mi_voldis.metrics import diagonal_pixels

run, data = sys.argv[1], sys.argv[2]
reach = float(sys.argv[3]) if len(sys.argv) > 3 else 0.03
cfg, ds, state, inputs = load_run(run, data)
full = state.fields["full"]
pts, real = vertex_positions(full)
world = inputs.space.to_world_np(pts)
box = None
for shape in ET.parse(os.path.join(data, "scene", "scene.xml")).getroot().iter("shape"):
    if shape.get("id") == "occluder":
        t = shape.find("transform")
        scale = np.array([float(x) for x in t.find("scale").get("value").split(",")])
        centre = np.array([float(x) for x in t.find("translate").get("value").split(",")])
        box = (centre - scale, centre + scale)
if box is None:
    raise SystemExit(f"{data}: the scene has no occluder")
gap = np.maximum(np.maximum(box[0] - world, world - box[1]), 0.0)
near = real & (np.linalg.norm(gap, axis=1) <= reach)
views = [ds.masked_train[k] for k in spread(len(ds.masked_train), VIEWS)]
args = (diagonal_pixels(cfg.hull_dilation, ds.size), cfg.hull_min_views, cfg.free_space_margin)
free = free_vertices(full, inputs.space, [ds.cameras[v] for v in views], ds.masks[views], *args)
print(f"vertices within {reach} of the occluder: {int(near.sum())}; marked free: {int((free & near).sum())}; "
      f"free in all: {int(free.sum())} of {int(real.sum())}")
heights = world[free & near][:, 1]
print(f"their heights (the pole stands 0 to {box[1][1]:.2f}):",
      np.round(np.percentile(heights, [0, 25, 50, 75, 100]), 3) if len(heights) else "-")
# which views take them: the free space of the 24 views less one, against all 24
for k, v in enumerate(views if os.environ.get("PER_VIEW") else []):
    rest = views[:k] + views[k + 1:]
    without = free_vertices(full, inputs.space, [ds.cameras[u] for u in rest], ds.masks[rest], *args)
    lost = free & near & ~without
    if lost.any():
        print(f"  view {v}: alone marks {int(lost.sum())} of them")
