"""hole_carve on RUN: bricks before / after allocation, and the vertices carved and made solid."""

import sys

import numpy as np
from kept_run import open_run

import mi_voldis  # noqa
from mi_voldis.bench.strategies import refit_config
from mi_voldis.fit import background as B
from mi_voldis.fit.lift import training_depths

run = sys.argv[1]
cfg = refit_config(run, "guided", ["hole_carve=true"] + sys.argv[2:])  # the carving it counts (off by default)
print("hole_carve", cfg.hole_carve, cfg.hole_carve_behind)
cfg, ds, state, inputs = open_run(run, cfg)
before = int((state.fields["full"].layout.table > 0).sum())
depth = training_depths(inputs, state, median=True)
state.fields["full"] = B.allocate_hidden_surface(inputs, state, depth)
after = int((state.fields["full"].layout.table > 0).sum())
print("bricks", before, after)
hull, pts, obj, refill, solid = B.background_regions(inputs, state, None, with_solid=True)
print(
    "hull",
    np.array(hull).sum(),
    "obj",
    np.array(obj).sum(),
    "refill",
    np.array(refill).sum(),
    "solid",
    np.array(solid).sum(),
    "solid&~obj",
    (np.array(solid) & ~np.array(obj)).sum(),
)
