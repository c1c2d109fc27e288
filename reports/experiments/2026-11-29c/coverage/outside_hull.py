"""#46: where the full field's weight lies on the object's pixels that the foreground coverage misses.

    python reports/experiments/2026-11-29c/coverage/outside_hull.py RUN VIEW   # RUN fitted with --keep-checkpoints

For every pixel of held-out VIEW that the true coverage gives the object (coverage > 0.5), the rays through
the pixel centre are marched through both fields of the finished run (evaluated loop mode, so a probe sees every
sample); each sample is put in the nearest stored vertex's region of the background's start
(mi_voldis.fit.background.background_regions): outside the visual hull, a kept hull vertex (some view sees it
unmasked), a refilled one, or the object's own. Printed for the pixels the coverage sum max(w_full - w_bg, 0)
finds (> 0.5) and for those it misses: the mean full-field weight in each region, and the mean coverage.
"""
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

run, view = sys.argv[1], int(sys.argv[2])
cfg = refit_config(run, "guided")
with open(os.path.join(run, "config.json")) as f:
    rec = json.load(f)["dataset"]
ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, 0.9, 0.99))
inputs = FitInputs.of(ds, cfg, "/tmp/none.npz", progress=False)
integrator = fit_integrator(inputs, state)
full = state.fields["full"]
hull, _, obj, refill = background_regions(inputs, state)
region = np.where(np.array(obj), 3, np.where(np.array(refill), 2, np.where(np.array(hull) > 0, 1, 0)))
names = ("outside the hull", "kept hull vertex", "refilled", "object's own")
plan = integrator.plan(("full", "bg"))
cf, cb = plan.sources.full, plan.sources.bg
origin = full.to_world[:3, 3]
scale = (np.array(full.shape) - 1) / np.diag(full.to_world)[:3]
truth = ds.coverage[view] > 0.5
py, px = np.nonzero(truth)
o, d = pixel_rays(ds.cameras[view], px + 0.5, py + 0.5)
samples = []


def probe(p, w, active, depth):
    samples.append((np.array(p), np.array(w[cf]), np.array(w[cb]), np.array(active)))


dr.set_flag(dr.JitFlag.SymbolicLoops, False)  # the probe runs once an iteration, on evaluated arrays
with dr.suspend_grad():
    rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d))
    march.forward(plan, rays, dr.full(mi.Float, 0.5, len(o)), probe=probe)
share = np.zeros((len(o), 4))
coverage = np.zeros(len(o))
for p, wf, wb, active in samples:
    p = p.T if p.shape[0] == 3 else p
    ijk = np.clip(np.rint((p - origin) * scale), 0, np.array(full.shape) - 1).astype(np.uint32)
    idx = np.array(full.layout.address(mi.UInt32(ijk[:, 0]), mi.UInt32(ijk[:, 1]), mi.UInt32(ijk[:, 2]),
                                       mi.Bool(active)))
    wf, wb = np.where(active, wf, 0.0), np.where(active, wb, 0.0)
    np.add.at(share, (np.arange(len(o)), region[idx]), wf)
    coverage += np.maximum(wf - wb, 0.0)
found = coverage > 0.5
print(f"{run} view {view}: {truth.sum()} object pixels, coverage finds {found.sum()}, misses {(~found).sum()}")
for label, sel in (("found", found), ("missed", ~found)):
    if sel.any():
        print(f"  {label}: coverage {coverage[sel].mean():.3f}; full-field weight "
              + ", ".join(f"{n} {share[sel, k].mean():.3f}" for k, n in enumerate(names)))
