"""The tiny tabletop (tests/conftest.py's TINY_FIT) fitted with free_space=true by the code of the checkout
ROOT; its final full field's packed values saved to OUT.npy (the dataset made once under DATA):

    python same_fit.py ROOT DATA OUT.npy
"""
import importlib
import os
import sys

import numpy as np

root, data, out = sys.argv[1:4]
if os.path.exists(out):
    raise SystemExit(f"error: {out} exists")
sys.path[:0] = [root, os.path.join(root, "tests")]  # the checkout's package and test settings
TINY_FIT = importlib.import_module("conftest").TINY_FIT
make_dataset = importlib.import_module("mi_voldis.synth.make").make_dataset
FitConfig = importlib.import_module("mi_voldis.fit.config").FitConfig
run_fit = importlib.import_module("mi_voldis.fit.run").run_fit
FitState = importlib.import_module("mi_voldis.fit.state").FitState
Adam = importlib.import_module("mi_voldis.optim.adam").Adam

if not os.path.exists(data):
    make_dataset(os.path.join(root, "scenes", "tabletop.xml"), data, views=9, resolution=(32, 24), spp=4,
                 progress=False)
run = out + ".run"
if os.path.exists(run):
    raise SystemExit(f"error: {run} exists")
run_fit(data, run, FitConfig.from_sources(None, TINY_FIT + ["free_space=true"]), progress=False,
        keep_checkpoints=True)
state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, 0.9, 0.99))
np.save(out, np.array(state.fields["full"].data))
