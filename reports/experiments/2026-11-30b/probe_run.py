"""A fitted run kept with --keep-checkpoints, loaded for the probes of this folder: its settings as a `guided`
refit reads them, its dataset, its final state and the fit's inputs."""
import json
import os

from mi_voldis.bench.strategies import refit_config
from mi_voldis.data import load_dataset
from mi_voldis.fit.fields import FitInputs
from mi_voldis.fit.state import FitState
from mi_voldis.optim.adam import Adam


def load_run(run, dataset=None):
    """(cfg, dataset, state, inputs) of ``run``; ``dataset``: another copy of its dataset to read (e.g. one
    with masks made from a box)."""
    cfg = refit_config(run, "guided")
    with open(os.path.join(run, "config.json")) as f:
        rec = json.load(f)["dataset"]
    ds = load_dataset(dataset or rec["path"], rec["format"], rec["holdout"])
    state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, 0.9, 0.99))
    return cfg, ds, state, FitInputs.of(ds, cfg, os.devnull, progress=False)
