"""The background layer of held-out view V and its alpha, side by side, as one PNG."""

import json
import sys

import numpy as np

import mi_voldis  # noqa
from mi_voldis.data import load_dataset
from mi_voldis.fit.config import FitConfig
from mi_voldis.fit.fields import FitInputs, fit_integrator
from mi_voldis.fit.state import FitState
from mi_voldis.io.images import display_to_uint8, write_png
from mi_voldis.optim.adam import Adam
from mi_voldis.render.views import render_camera

run, v, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
cfg = FitConfig.from_sources(run + "/config.json", [])
rec = json.load(open(run + "/config.json"))["dataset"]
ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
state = FitState.load(run + "/checkpoints/last.npz", Adam({}, 0.9, 0.99))
inputs = FitInputs.of(ds, cfg, "/tmp/s46/diag_state.npz", True)
integ = fit_integrator(inputs, state)
r = render_camera(integ, ds.cameras[v], ("bg",))["bg"]
rgb, a = r[0], r[1]
img = np.concatenate([np.clip(rgb, 0, 1), np.repeat(a[..., None], 3, -1)], 1)
write_png(out, display_to_uint8(img))
