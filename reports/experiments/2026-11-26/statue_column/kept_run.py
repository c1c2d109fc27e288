"""A finished run kept with --keep-checkpoints, reopened as the scripts beside this one use it."""

import json
import os

import mi_voldis  # noqa  (the variant)
from mi_voldis.data import load_dataset
from mi_voldis.fit.config import FitConfig
from mi_voldis.fit.fields import FitInputs, fit_integrator
from mi_voldis.fit.state import FitState
from mi_voldis.optim.adam import Adam


def open_run(run, cfg=None):
    """(cfg, dataset, final state, fit inputs) of ``run``: ``cfg`` (default: the run's config.json) over its
    dataset as the fit read it; the inputs write no checkpoint."""
    cfg = cfg or FitConfig.from_sources(os.path.join(run, "config.json"), [])
    with open(os.path.join(run, "config.json")) as f:
        rec = json.load(f)["dataset"]
    ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
    state = FitState.load(os.path.join(run, "checkpoints", "last.npz"),
                          Adam({}, cfg.adam_beta1, cfg.adam_beta2, warmup=cfg.lr_warmup))
    return cfg, ds, state, FitInputs.of(ds, cfg, os.devnull, True)


def run_integrator(run):
    """(dataset, the voldis integrator of ``run``'s final state)."""
    _, ds, state, inputs = open_run(run)
    return ds, fit_integrator(inputs, state)
