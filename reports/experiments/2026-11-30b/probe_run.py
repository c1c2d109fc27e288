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


def knockout_sheet(inputs, state, background, classes, views, out):
    """Renders ``views`` of ``background`` (a field) with each of ``classes`` ({name: Bool per stored vertex,
    NumPy}) emptied in turn, one row each, into the PNG ``out`` (twice the size); prints each class's count."""
    import mitsuba as mi
    import numpy as np
    from PIL import Image

    from mi_voldis.fit.background import emptied
    from mi_voldis.fit.fields import fit_integrator
    from mi_voldis.render.views import render_camera
    tiles = []
    for name, region in classes.items():
        state.fields["bg"] = emptied(inputs, state, background, mi.Bool(region))
        integrator = fit_integrator(inputs, state)
        row = [np.clip(render_camera(integrator, inputs.ds.cameras[v], ("bg",))["bg"][0], 0, 1) for v in views]
        tiles.append(np.concatenate(row, 1))
        print(f"{name}: {int(region.sum())} vertices emptied", flush=True)
    image = Image.fromarray((np.concatenate(tiles, 0) * 255).astype(np.uint8))
    image.resize((2 * image.width, 2 * image.height)).save(out)
