"""The background of RUN refitted with today's defaults (and --set ...) into a new folder OUT, its
final state kept in OUT/checkpoints.
"""

import os
import shutil
import sys

from kept_run import open_run

import mi_voldis  # noqa
from mi_voldis.bench.strategies import refit_config
from mi_voldis.fit.train import fit

run, out = sys.argv[1], sys.argv[2]
sets = sys.argv[3:]
if os.path.exists(out):
    raise SystemExit(f"error: {out} exists (give a new folder)")
cfg = refit_config(run, "guided", sets)
cfg, ds, state, _ = open_run(run, cfg)
state.fields.pop("bg", None)
state.hull_points = state.prior = state.prior_keys = state.occupancy = None
state.adam.reset()
os.makedirs(out + "/checkpoints", exist_ok=True)
state.save(out + "/checkpoints/last.npz", "bg", 0)
inputs, state = fit(ds, out + "/checkpoints/last.npz", cfg, resume=True, progress=False)
shutil.copy(run + "/config.json", out + "/config.json")
print("done")
