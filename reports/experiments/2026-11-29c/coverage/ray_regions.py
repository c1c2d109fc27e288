"""#46: every sample's full and background weight along the rays of chosen pixels of a held-out view, with the
nearest stored vertex's region of the background's start (out: outside the hull; kept: a hull vertex some view
sees unmasked; refill; obj: the object's own; "C:" where the clear strategy's object_ray_keys would empty it).

    python reports/experiments/2026-11-29c/coverage/ray_regions.py RUN VIEW X,Y ...   # RUN: --keep-checkpoints
"""
# ruff: noqa: E402, E501, E702, E741  (a probe kept as it ran)
import json
import os
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

import mi_voldis  # noqa: F401  (sets the variant)
from mi_voldis.bench.strategies import refit_config
from mi_voldis.cameras import pixel_rays
from mi_voldis.data import load_dataset
from mi_voldis.device import from_numpy
from mi_voldis.fit.background import background_regions
from mi_voldis.fit.fields import FitInputs, fit_integrator
from mi_voldis.fit.state import FitState
from mi_voldis.optim.adam import Adam
from mi_voldis.render import march

run, v = sys.argv[1], int(sys.argv[2])
pix = [tuple(int(x) for x in s.split(",")) for s in sys.argv[3:]]  # x,y
cfg = refit_config(run, "guided")
rec = json.load(open(os.path.join(run, "config.json")))["dataset"]
ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, 0.9, 0.99))
inputs = FitInputs.of(ds, cfg, "/tmp/none.npz", progress=False)
integ = fit_integrator(inputs, state)
full = state.fields["full"]
hull, points, obj, refill = background_regions(inputs, state)
H, O, R = np.array(hull) > 0, np.array(obj), np.array(refill)
from mi_voldis.fit.lift import keys_mask, object_ray_keys, training_depths

dep = training_depths(inputs, state)
carved = object_ray_keys(inputs, full, [u for u in dep if u in set(ds.masked_train)], dep)
C = np.array(keys_mask(full, carved))
print("carved", C.sum(), "carved outside hull", (C & ~H).sum())
print("hull", H.sum(), "obj", O.sum(), "refill", R.sum(), "kept in hull", (H & ~R).sum())
plan = integ.plan(("full", "bg"))
cf, cb = plan.sources.full, plan.sources.bg
m = full.to_world
origin = np.array(m[:3, 3]); scale = (np.array(full.shape) - 1) / np.diag(m)[:3]
px = np.array([p[0] for p in pix]) + 0.5
py = np.array([p[1] for p in pix]) + 0.5
o, d = pixel_rays(ds.cameras[v], px, py)
rec_ = []
def probe(p, w, active, depth):
    rec_.append((np.array(p), np.array(w[cf]), np.array(w[cb]), np.array(active)))
dr.set_flag(dr.JitFlag.SymbolicLoops, False)
with dr.suspend_grad():
    rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d))
    march.forward(plan, rays, dr.full(mi.Float, 0.5, len(o)), probe=probe)
for r in range(len(o)):
    print(f"pixel {pix[r]}")
    for p, wf, wb, a in rec_:
        if not a[r]:
            continue
        wf_, wb_ = float(wf[r]), float(wb[r])
        if max(wf_, wb_) > 0.01:
            ps = np.array(p)[:, r] if np.array(p).shape[0] == 3 else np.array(p)[r]
            ijk = np.round((ps - origin) * scale).astype(int)
            idx = int(np.array(full.layout.address(mi.UInt32(int(ijk[0])), mi.UInt32(int(ijk[1])), mi.UInt32(int(ijk[2])), mi.Bool(True)))[0])
            cat = ("C:" if C[idx] else "") + ("obj" if O[idx] else "refill" if R[idx] else "kept" if H[idx] else "out")
            pw = inputs.space.to_world_np(ps[None])[0]
            print(f"  y {pw[1]:.3f} t {np.linalg.norm(pw - o[r]):.3f} w_full {wf_:.3f} w_bg {wb_:.3f} {cat}")
