"""The regions the background starts from (the hull, the object's voxels, the refilled voxels, the dense voxels
kept from the full field) for a fitted run's full field, and where the kept ones lie from the object's centre.

    python reports/experiments/2026-11-29/sh_gate/regions.py RUN     # RUN fitted with --keep-checkpoints
"""
import json
import os
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

import mi_voldis  # noqa
from mi_voldis.bench.strategies import refit_config
from mi_voldis.data import load_dataset
from mi_voldis.field_state import density_raw_for_alpha, vertex_positions
from mi_voldis.fit.background import background_regions, voxel_of
from mi_voldis.fit.fields import FitInputs
from mi_voldis.fit.state import FitState
from mi_voldis.optim.adam import Adam

run = sys.argv[1]
cfg = refit_config(run, "guided")
rec = json.load(open(os.path.join(run, "config.json")))["dataset"]
ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, 0.9, 0.99))
state.fields.pop("bg", None)
inputs = FitInputs.of(ds, cfg, "/tmp/none.npz", progress=False)
hull, points, obj, refill = background_regions(inputs, state)
full = state.fields["full"]
raw = np.array(dr.gather(mi.Float, full.data, dr.arange(mi.UInt32, full.vertices) * full.width))
h, o, r = np.array(hull) > 0, np.array(obj), np.array(refill)
thr = density_raw_for_alpha(cfg.object_alpha, voxel_of(full), full.density_scale)
print(run, "hull", h.sum(), "obj", o.sum(), "refill", r.sum(), "dense in hull", (h & (raw > thr)).sum(),
      "dense in hull not obj", (h & (raw > thr) & ~o).sum(), "dense in hull not refilled", (h & (raw > thr) & ~r).sum())

pos, real = vertex_positions(full)
world = inputs.space.to_world_np(pos)
kept = h & (raw > thr) & ~r
c = world[o].mean(0)
rad = np.linalg.norm(world[o] - c, axis=1)
print(" object centre", np.round(c, 3), "object radius (90%)", np.round(np.quantile(rad, 0.9), 3))
d = np.linalg.norm(world[kept] - c, axis=1)
print(" kept dense: distance quantiles", np.round(np.quantile(d, [0.1, 0.5, 0.9]), 3),
      "within 1.2 r:", int((d < 1.2 * np.quantile(rad, 0.9)).sum()))
