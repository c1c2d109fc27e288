"""#46: which vertices of a run's fitted `guided` background (after its refit) draw what is left in the hole. Renders
VIEWS of the run's final background with classes of the visual hull's vertices (as the background's start marks them:
`start_harmonic` on the run's final full field) emptied in turn, one row each: none, the kept ones (some view sees
them unmasked), the kept ones within 2 vertices of the object's, the refilled ones that are not the object's, the
object's own. Writes OUT (a PNG; refuses an existing file) and prints each class's vertex count.

    python final_knockout.py RUN OUT.png VIEWS
"""
import dataclasses
import os
import sys

import mitsuba as mi
import numpy as np

import mi_voldis  # noqa: F401

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-11-30b"))
from probe_run import knockout_sheet, load_run  # noqa: E402

from mi_voldis.field.state import dilate_vertices, neighbour_vertices, vertex_positions  # noqa: E402
from mi_voldis.fit.background import start_harmonic  # noqa: E402
from mi_voldis.fit.train import object_fringe  # noqa: E402

if len(sys.argv) != 4:
    raise SystemExit("usage: python final_knockout.py RUN OUT.png VIEWS")
run, out = sys.argv[1], sys.argv[2]
if os.path.lexists(out):
    raise SystemExit(f"error: {out} exists; give another OUT")
views = [int(x) for x in sys.argv[3].split(",")]
cfg, ds, state, inputs = load_run(run)
final = state.fields["bg"]
depths = {}
if cfg.fringe_contrast > 0:
    inputs = dataclasses.replace(inputs, fringe=object_fringe(inputs, state, depths, False))
hull, obj, refill, _ = start_harmonic(inputs, state, depths)
full = state.fields["full"]
if full.vertices != final.vertices or not np.array_equal(full.layout.table, final.layout.table):
    raise SystemExit("error: the final background's lattice is not the start's")
_, real = vertex_positions(full)
hull_np, obj_np, refill_np = (np.array(hull) > 0) & real, np.array(obj), np.array(refill)
near = np.array(dilate_vertices(mi.Bool(obj_np), neighbour_vertices(full), 2))
classes = {"none": np.zeros_like(hull_np), "kept": hull_np & ~refill_np,
           "kept within 2 of the object's": hull_np & ~refill_np & near,
           "refilled, not the object's": hull_np & refill_np & ~obj_np, "the object's": obj_np}
knockout_sheet(inputs, state, final, classes, views, out)
