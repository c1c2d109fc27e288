"""#46: garden's hull fill axis weights with the box masks, as the package reads them now (the hull's median) and
as it read them before c248395 (the mean of the hull's points, a step of 1e-3 of their spread).

    python fill_axis.py RUN MASKED_DATA      # RUN: garden's fit kept with --keep-checkpoints
"""
# ruff: noqa: E402
import os
import sys

import numpy as np

import mi_voldis  # noqa: F401  (sets the variant)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from probe_run import load_run

from mi_voldis.cameras import world_up
from mi_voldis.field_state import neighbour_vertices
from mi_voldis.fit.background import fill_weights, hull_region
from mi_voldis.fit.lift import training_depths

cfg, ds, state, inputs = load_run(sys.argv[1], sys.argv[2])
full = state.fields["full"]
_, points = hull_region(inputs, full, neighbour_vertices(full), training_depths(inputs, state, median=True))
world = inputs.space.to_world_np(points)
print("now (x/y/z):", [round(x, 3) for x in fill_weights(inputs, full, points)[0::2]])
up = world_up([ds.cameras[i] for i in ds.train])
centre, step = world.mean(0), 1e-3 * float(np.ptp(world, 0).max())
ends = inputs.space.from_world_np(np.stack([centre, centre + step * up]))
local = np.linalg.solve(full.to_world[:3, :3], ends[1] - ends[0]) * (np.array(full.shape) - 1)
u = local / np.linalg.norm(local)
print("before (x/y/z):", [round(float(1 - u[a] ** 2), 3) for a in range(3)],
      f"; the hull points' mean {np.abs(centre).max():.3g} out, median {np.abs(np.median(world, 0)).max():.3g}")
