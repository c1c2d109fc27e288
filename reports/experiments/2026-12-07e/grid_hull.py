"""Of a finished run's full field (RUN/full_grid.npz), the bricks the visual hull reaches and how many the fit left
unallocated (what mi_voldis.fit.background.allocate_hull adds)."""
import json
import os
import sys

import numpy as np

import mi_voldis  # noqa: F401
from mi_voldis.bench.strategies import refit_config
from mi_voldis.data import load_dataset
from mi_voldis.field import bricks
from mi_voldis.fit.background import hull_bricks
from mi_voldis.fit.fields import FitInputs

for arg in sys.argv[1:]:  # RUN, or RUN:DATA to read the run with another copy of its dataset (other masks)
    run, _, data = arg.partition(":")
    cfg = refit_config(run, "guided")
    with open(os.path.join(run, "config.json")) as f:
        rec = json.load(f)["dataset"]
    ds = load_dataset(data or rec["path"], rec["format"], rec["holdout"])
    inputs = FitInputs.of(ds, cfg, os.devnull, progress=False)
    g = np.load(os.path.join(run, "full_grid.npz"))
    layout = bricks.Layout(tuple(int(v) for v in g["vertices"]), int(g["brick"]), g["table"])
    lo, hi = g["bbox"]
    to_world = np.diag(list(hi - lo) + [1.0])
    to_world[:3, 3] = lo
    need = hull_bricks(inputs, layout, to_world)
    missing = need & (layout.table == 0)
    print(f"{os.path.basename(run)} brick {layout.brick} vertices {layout.shape[0]} hull bricks {need.sum()} "
          f"unallocated {missing.sum()} ({missing.sum() / max(need.sum(), 1):.3f}); "
          f"field {int((layout.table > 0).sum())}", flush=True)
