"""#46: the hull fill's axis weights (`mi_voldis.fit.background.fill_weights`) as the package computes them (the
world's up carried into the field's lattice at the mean of the hull's points, a step of 1e-3 of their spread) and
at the median point with a step of 1e-3 of their 10-90% spread. In a contracted space the hull can reach the
shell's far end, and the mean with it.

    python fill_up.py RUN [RUN ...]      # RUN: a fit kept with --keep-checkpoints
"""
# ruff: noqa: E402
import os
import sys

import numpy as np

import mi_voldis  # noqa: F401  (sets the variant)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from probe_run import load_run  # noqa: E402

from mi_voldis.cameras import world_up
from mi_voldis.field_state import neighbour_vertices
from mi_voldis.fit.background import fill_weights, hull_region
from mi_voldis.fit.lift import training_depths


def local_up(inputs, field, world, centre, step):
    up = world_up([inputs.ds.cameras[i] for i in inputs.ds.train])
    ends = inputs.space.from_world_np(np.stack([centre, centre + step * up]))
    local = np.linalg.solve(field.to_world[:3, :3], ends[1] - ends[0]) * (np.array(field.shape) - 1)
    return local / np.linalg.norm(local)


for run in sys.argv[1:]:
    cfg, ds, state, inputs = load_run(run)
    full = state.fields["full"]
    _, points = hull_region(inputs, full, neighbour_vertices(full), training_depths(inputs, state, median=True))
    world = inputs.space.to_world_np(points)
    w = fill_weights(inputs, full, points)
    spread = float((np.percentile(world, 90, 0) - np.percentile(world, 10, 0)).max())
    u_med = local_up(inputs, full, world, np.median(world, 0), 1e-3 * spread)
    v = cfg.hull_fill_vertical
    w_med = [float(1.0 - (1.0 - v) * u_med[a] ** 2) for a in range(3)]
    print(f"{os.path.basename(run.rstrip('/'))}: space {inputs.space.kind}; hull points' mean "
          f"{np.abs(world.mean(0)).max():.3g} out, median {np.abs(np.median(world, 0)).max():.3g}; weights x/y/z "
          f"as fitted {[round(x, 3) for x in (w[0::2] if w else [1, 1, 1])]}, at the median "
          f"{[round(x, 3) for x in w_med]}", flush=True)
