"""#46 probe: the masks' free space on a fitted run's final lattice, with the masks alone and with its full
field telling an occluder's gaps from notches (field_gap_depth), and how many of each lie within R of the
scene's occluder (DATA/scene/scene.xml's `occluder`, where it has one).

    python told_gaps.py RUN DATA [R]
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
from mi_voldis.fit.fields import fit_integrator
from mi_voldis.fit.free_space import VIEWS, field_gap_depth, free_vertices
from mi_voldis.metrics import diagonal_pixels

run, data = sys.argv[1], sys.argv[2]
reach = float(sys.argv[3]) if len(sys.argv) > 3 else 0.03
cfg, ds, state, inputs = load_run(run, data)
full = state.fields["full"]
views = [ds.masked_train[k] for k in spread(len(ds.masked_train), VIEWS)]
args = ([ds.cameras[v] for v in views], ds.masks[views], diagonal_pixels(cfg.hull_dilation, ds.size),
        cfg.hull_min_views, cfg.free_space_margin)
alone = free_vertices(full, inputs.space, *args)
told = free_vertices(full, inputs.space, *args, field_gap_depth(fit_integrator(inputs, state)))
near = np.zeros(len(alone), bool)
for shape in ET.parse(os.path.join(data, "scene", "scene.xml")).getroot().iter("shape"):
    if shape.get("id") == "occluder":
        t = shape.find("transform")
        scale = np.array([float(x) for x in t.find("scale").get("value").split(",")])
        centre = np.array([float(x) for x in t.find("translate").get("value").split(",")])
        pts, real = vertex_positions(full)
        world = inputs.space.to_world_np(pts)
        gap = np.maximum(np.maximum(centre - scale - world, world - centre - scale), 0.0)
        near = real & (np.linalg.norm(gap, axis=1) <= reach)
print(f"{os.path.basename(run)}: free with the masks alone {int(alone.sum())}, told by the field {int(told.sum())} "
      f"(only told {int((told & ~alone).sum())}, only alone {int((alone & ~told).sum())}); within {reach} of the "
      f"occluder: {int(near.sum())} vertices, free alone {int((alone & near).sum())}, told {int((told & near).sum())}")
