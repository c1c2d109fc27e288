"""What the scripts of this folder share: their ``--set KEY=VALUE`` arguments, and a family run's background
refitted from its checkpoint with the `guided` row's settings plus those (or read as the run left it)."""
import json
import os
import tempfile


def split_sets(argv):
    """(the values of every ``--set``, the other arguments in order)."""
    sets = [argv[k + 1] for k, a in enumerate(argv) if a == "--set"]
    plain = [a for k, a in enumerate(argv) if a != "--set" and (k == 0 or argv[k - 1] != "--set")]
    return sets, plain


def refitted(run, sets, refit=True):
    """(dataset, config, inputs, state, integrator) of RUN (a fit kept with --keep-checkpoints) with its
    background refitted under ``sets`` (or, with ``refit`` false, its own background); one line and exit
    on a run without checkpoints or a bad setting."""
    if not os.path.isfile(os.path.join(run, "checkpoints", "last.npz")):
        raise SystemExit(f"error: {run}: no checkpoints/last.npz (a fit kept with --keep-checkpoints)")
    from mi_voldis.bench.strategies import refit_config
    from mi_voldis.data import load_dataset
    from mi_voldis.fit.fields import fit_integrator
    from mi_voldis.fit.state import FitState
    from mi_voldis.fit.train import fit
    from mi_voldis.optim.adam import Adam
    try:
        cfg = refit_config(run, "guided", sets)
    except ValueError as e:
        raise SystemExit(f"error: {e}") from None
    with open(os.path.join(run, "config.json")) as f:
        record = json.load(f)["dataset"]
    ds = load_dataset(record["path"], record["format"], record["holdout"])
    state = FitState.load(os.path.join(run, "checkpoints", "last.npz"),
                          Adam({}, cfg.adam_beta1, cfg.adam_beta2, warmup=cfg.lr_warmup))
    if refit:
        state.fields.pop("bg", None)
        state.hull_points = state.prior = state.prior_keys = state.occupancy = None
        state.adam.reset()
    with tempfile.TemporaryDirectory() as tmp:  # the state is resumed from a copy: the run is only read
        checkpoint = os.path.join(tmp, "state.npz")
        state.save(checkpoint, "bg" if refit else "done", 0)
        inputs, state = fit(ds, checkpoint, cfg, resume=True, progress=False)
    return ds, cfg, inputs, state, fit_integrator(inputs, state)
