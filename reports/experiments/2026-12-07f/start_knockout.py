"""#46: which vertices of the `guided` background's start (before its refit) draw the glassy ghost. Renders VIEWS of
the start (`start_harmonic` on RUN's final full field, as a refit begins) with classes of the visual hull's vertices
emptied in turn, one row each: none, the kept ones (some view sees them unmasked), the kept ones denser than 0.2 a
voxel, the refilled ones that are not the object's, those seen only through the object's dark fringe. Writes OUT
(a PNG; refuses an existing file) and prints each class's vertex count.

    python start_knockout.py RUN DATA OUT.png VIEWS
"""
import dataclasses
import os
import sys

import numpy as np

import mi_voldis  # noqa: F401

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-11-30b"))
from probe_run import knockout_sheet, load_run  # noqa: E402

from mi_voldis.field.state import density_of, vertex_positions  # noqa: E402
from mi_voldis.fit.background import fringe_vertices, start_harmonic, voxel_of  # noqa: E402
from mi_voldis.fit.train import object_fringe  # noqa: E402

if len(sys.argv) != 5:
    raise SystemExit("usage: python start_knockout.py RUN DATA OUT.png VIEWS")
run, data, out = sys.argv[1], sys.argv[2], sys.argv[3]
if os.path.lexists(out):
    raise SystemExit(f"error: {out} exists; give another OUT")
views = [int(x) for x in sys.argv[4].split(",")]
cfg, ds, state, inputs = load_run(run, data)
state.fields.pop("bg", None)
state.hull_points = state.prior = state.prior_keys = state.occupancy = None
depths = {}
if cfg.fringe_contrast > 0:
    inputs = dataclasses.replace(inputs, fringe=object_fringe(inputs, state, depths, False))
hull, obj, refill, _ = start_harmonic(inputs, state, depths)
full = state.fields["full"]
_, real = vertex_positions(full)
alpha = 1 - np.exp(-np.log1p(np.exp(np.minimum(density_of(full), 30))) * full.density_scale * voxel_of(full))
hull_np, obj, refill = (np.array(hull) > 0) & real, np.array(obj), np.array(refill)
fringe = (np.array(fringe_vertices(inputs, state, hull, depths)) if inputs.fringe is not None
          else np.zeros_like(obj))
classes = {"none": np.zeros_like(hull_np), "kept": hull_np & ~refill,
           "kept, denser than 0.2": hull_np & ~refill & (alpha > 0.2),
           "refilled, not the object's": hull_np & refill & ~obj, "seen through the fringe alone": hull_np & fringe}
start = state.fields["bg"]
knockout_sheet(inputs, state, start, classes, views, out)
