"""How the background's start divides RUN's hull (optionally with another copy of its dataset, e.g. box masks): stored
vertices in the hull, never seen unmasked, the object's own (emptied), refilled (inpainted), kept; and the full
field's opacity a voxel in each (the object's density where the start leaves it).

    python regions.py RUN [DATA]
"""
# ruff: noqa: E402
import os
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

import mi_voldis  # noqa: F401

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.activations import softplus
from mi_voldis.field_state import neighbour_vertices
from mi_voldis.fit.background import background_regions, voxel_of

cfg, ds, state, inputs = load_run(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else None)
full = state.fields["full"]
hull, points, obj, refill = background_regions(inputs, state, neighbour_vertices(full))
raw = np.array(dr.gather(mi.Float, full.data, dr.arange(mi.UInt32, full.vertices) * full.width))
alpha = 1 - np.exp(-np.array(softplus(mi.Float(raw))) * full.density_scale * voxel_of(full))
inside, own, filled = np.array(hull) > 0, np.array(obj), np.array(refill) & (np.array(hull) > 0)
for name, part in (("hull", inside), ("object (emptied)", own), ("refilled, not object", filled & ~own),
                   ("kept (seen)", inside & ~filled)):
    a = alpha[part]
    print(f"{name}: {part.sum()} vertices; opacity a voxel: mean {a.mean():.3f}, above 0.2: {(a > 0.2).sum()}")
