"""hole_carve on RUN: bricks before / after allocation, and the vertices carved and made solid."""

import json
import sys

import numpy as np

import mi_voldis  # noqa
from mi_voldis.bench.strategies import refit_config
from mi_voldis.data import load_dataset
from mi_voldis.fit import background as B
from mi_voldis.fit.fields import FitInputs
from mi_voldis.fit.lift import training_depths
from mi_voldis.fit.state import FitState
from mi_voldis.optim.adam import Adam

run = sys.argv[1]
cfg = refit_config(run, "guided")
print("hole_carve", cfg.hole_carve, cfg.hole_carve_behind)
rec = json.load(open(run + "/config.json"))["dataset"]
ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
state = FitState.load(run + "/checkpoints/last.npz", Adam({}, 0.9, 0.99))
inputs = FitInputs.of(ds, cfg, "/tmp/s46/diag_state.npz", True)
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
