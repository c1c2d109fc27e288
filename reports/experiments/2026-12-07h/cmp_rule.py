"""The free vertices of a run's checkpoint by the code of the checkout ROOT (its 24 spread masked views, the
run's settings, the masks alone), their count and seconds:

    python cmp_rule.py ROOT RUN OUT.npy
"""
import importlib
import json
import os
import sys
import time

import numpy as np

root, run, out = sys.argv[1:4]
if os.path.exists(out):
    raise SystemExit(f"error: {out} exists")
sys.path.insert(0, root)  # the checkout's package, not the installed one
load_dataset = importlib.import_module("mi_voldis.data").load_dataset
spread = importlib.import_module("mi_voldis.data.types").spread
FitConfig = importlib.import_module("mi_voldis.fit.config").FitConfig
FitInputs = importlib.import_module("mi_voldis.fit.fields").FitInputs
free_space = importlib.import_module("mi_voldis.fit.free_space")
FitState = importlib.import_module("mi_voldis.fit.state").FitState
diagonal_pixels = importlib.import_module("mi_voldis.metrics").diagonal_pixels
Adam = importlib.import_module("mi_voldis.optim.adam").Adam

with open(os.path.join(run, "config.json")) as f:
    rec = json.load(f)
cfg = FitConfig.from_sources(os.path.join(run, "config.json"), [])
ds = load_dataset(rec["dataset"]["path"], rec["dataset"]["format"], rec["dataset"]["holdout"])
state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, 0.9, 0.99))
inputs = FitInputs.of(ds, cfg, os.devnull, progress=False)
views = [ds.masked_train[k] for k in spread(len(ds.masked_train), free_space.VIEWS)]
t = time.perf_counter()
free = free_space.free_vertices(state.fields["full"], inputs.space, [ds.cameras[v] for v in views], ds.masks[views],
                                diagonal_pixels(cfg.hull_dilation, ds.size), cfg.hull_min_views,
                                cfg.free_space_margin)
print(root, run, int(free.sum()), f"{time.perf_counter() - t:.1f} s")
np.save(out, free)
