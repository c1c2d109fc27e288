"""Seconds of the masks' free space on a run's checkpoint (its last lattice): the masks alone, then told by its
full field (field_gap_depth), each timed twice (the first call compiles the kernels).

    python time_marking.py RUN
"""
import json
import os
import sys
import time

import mi_voldis  # noqa
from mi_voldis.data import load_dataset
from mi_voldis.fit.config import FitConfig
from mi_voldis.fit.fields import FitInputs, fit_integrator
from mi_voldis.fit.free_space import training_free_space
from mi_voldis.fit.state import FitState
from mi_voldis.optim.adam import Adam

run = sys.argv[1]
with open(os.path.join(run, "config.json")) as f:
    rec = json.load(f)["dataset"]
cfg = FitConfig.from_sources(os.path.join(run, "config.json"), ["free_space=true"])
ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, 0.9, 0.99))
inputs = FitInputs.of(ds, cfg, os.devnull, progress=False)
full = state.fields["full"]
integrator = fit_integrator(inputs, state)
for label, fitted in [("masks alone", None), ("told by the field", integrator)] * 2:
    t = time.perf_counter()
    free = training_free_space(inputs, full, fitted)
    print(f"{label}: {int(free.sum())} of {full.vertices} vertices free, {time.perf_counter() - t:.1f} s")
