"""#46 item 3: where the background's haze lies in garden's hole. Refits RUN's background as
`bench.strategies RUN guided OUT DATA --refit` does (keeping the refitted state in OUT/state.npz; a second call
reuses it), then for held-out VIEWS writes OUT/hazeNNN.png (the background render, its haze map
sum_i w_i [t_i < 0.9 t_med] x 4 in red, the scored hole outlined) and prints the haze inside the hole and
outside it, and inside split by the background's median depth against the filled depth of the surfaces around
the hole (nearer than 0.9 of it: a stump standing in the hole; else on the surface).

    python haze_map.py RUN OUT DATA VIEWS [KEY=VALUE ...]
"""
# ruff: noqa: E402
import os
import shutil
import sys

import numpy as np

import mi_voldis  # noqa: F401

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.bench.strategies import refit_config
from mi_voldis.fit.fields import fit_integrator
from mi_voldis.fit.state import FitState
from mi_voldis.fit.train import fit
from mi_voldis.fit.visibility import hidden_depth
from mi_voldis.io.images import write_png
from mi_voldis.masks3d import dilate
from mi_voldis.metrics import score_dilation
from mi_voldis.optim.adam import Adam
from mi_voldis.render.surface import front_weight
from mi_voldis.render.views import render_camera

run, out, data, views = sys.argv[1], sys.argv[2], sys.argv[3], [int(v) for v in sys.argv[4].split(",")]
sets = sys.argv[5:]
os.makedirs(out, exist_ok=True)
kept = os.path.join(out, "state.npz")
cfg = refit_config(run, "guided", sets)
_, ds, _, _ = load_run(run, data)
if not os.path.exists(kept):
    state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, cfg.adam_beta1, cfg.adam_beta2))
    state.fields.pop("bg", None)
    state.hull_points = state.prior = state.prior_keys = state.occupancy = None
    state.adam.reset()
    work = os.path.join(out, "work.npz")
    state.save(work, "bg", 0)
    fit(ds, work, cfg, resume=True, progress=False)
    shutil.move(work, kept)
inputs, state = fit(ds, kept, cfg, resume=True, progress=False)
integrator = fit_integrator(inputs, state)
dil = score_dilation(ds.size)
for v in views:
    cam = ds.cameras[v]
    region = dilate(ds.masks[v], dil)
    front, hit = front_weight(integrator, cam, layer="bg")
    bg = render_camera(integrator, cam, ("bg", "full"))
    rgb, _, depth = bg["bg"]
    fdepth = bg["full"][2]
    filled = hidden_depth(cam, np.where(hit, fdepth, np.nan), ds.masks[v], region)
    inside, outside = region & hit, ~region & hit
    ring = dilate(region, dil + int(np.ceil(0.03 * np.hypot(*ds.size)))) & ~region & hit
    stump = inside & (depth < 0.9 * filled) if filled is not None else inside & False
    print(f"view {v}: haze in the hole {front[inside].mean():.3f} (n {inside.sum()}), "
          f"outside {front[outside].mean():.3f}, in a ring 3% of the diagonal around it "
          f"{front[ring].mean():.3f};"
          f" in the hole nearer than 0.9 x the filled depth: share {stump.sum() / max(inside.sum(), 1):.2f}, haze "
          f"{front[stump].mean() if stump.any() else float('nan'):.3f}; on the surface "
          f"{front[inside & ~stump].mean():.3f}")
    shown = np.clip(rgb, 0, 1).copy()
    heat = np.zeros_like(shown)
    heat[..., 0] = np.clip(4 * front, 0, 1)
    edge = region & dilate(~region, 1)
    for img in (shown, heat):
        img[edge] = [0, 1, 0]
    write_png(os.path.join(out, f"haze{v:03d}.png"), (np.concatenate([shown, heat], 1) * 255).round().astype(np.uint8))
