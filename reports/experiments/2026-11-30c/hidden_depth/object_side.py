"""#46 item 3: where the object's voxels (those the background empties) lie against the surface the object hides,
by the masked views' vote (`hole_shell`: filled depth from around each mask): in front of it, at it (behind but not
far: the hidden surface's shell) or far behind. With box masks the table top under the vase is never seen
unmasked and shows on masked rays, so it counts as the object's and is emptied.

    python object_side.py RUN [DATA]
"""
# ruff: noqa: E402
import os
import sys

import numpy as np

import mi_voldis  # noqa: F401

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.field_state import neighbour_vertices
from mi_voldis.fit.background import background_regions, hole_shell

cfg, ds, state, inputs = load_run(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else None)
full = state.fields["full"]
depths = {}
hull, points, obj, refill = background_regions(inputs, state, neighbour_vertices(full), depths=depths)
carve, solid = hole_shell(inputs, full, obj, depths)
o, c, s = np.array(obj), np.array(carve), np.array(solid)
n = o.sum()
print(f"object voxels {n}: in front of the hidden surface or far behind {c.sum()} ({c.sum() / n:.2f}), "
      f"at it (behind, not far) {s.sum()} ({s.sum() / n:.2f}), neither (no vote) {(o & ~c & ~s).sum()}")
