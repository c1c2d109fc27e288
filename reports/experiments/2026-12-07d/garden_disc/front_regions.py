"""#46 item 3: in which region of the background's start garden's hole haze lies. For held-out VIEWS, the rays
through the scored hole (the mask dilated as the bench scores it) are marched through the background kept by
`disc_haze.py` (OUT/state.npz); each sample's weight in front of 0.9 of the ray's median depth (the haze figure's
weight) is put in the nearest stored vertex's region (mi_voldis.fit.background.background_regions): outside the
visual hull, a kept hull vertex (some view sees it unmasked), a refilled one, or the object's own. Printed per view
and summed: the mean front weight per hole ray in each region, for the hole's metal and wood pixels (told apart by
the background layer's colour as in `disc_haze.py`) and for all of it.

    python front_regions.py RUN OUT DATA VIEWS
"""
# ruff: noqa: E402
import os
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

import mi_voldis  # noqa: F401

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.bench.strategies import refit_config
from mi_voldis.cameras import pixel_rays
from mi_voldis.device import from_numpy
from mi_voldis.fit.background import background_regions
from mi_voldis.fit.fields import fit_integrator
from mi_voldis.fit.train import fit
from mi_voldis.metrics import dilate, score_dilation
from mi_voldis.render import march
from mi_voldis.render.surface import median_points
from mi_voldis.render.views import render_camera

run, out, data, views = sys.argv[1], sys.argv[2], sys.argv[3], [int(v) for v in sys.argv[4].split(",")]
cfg = refit_config(run, "guided")
_, ds, _, _ = load_run(run, data)
inputs, state = fit(ds, os.path.join(out, "state.npz"), cfg, resume=True, progress=False)
integrator = fit_integrator(inputs, state)
full = state.fields["full"]
hull, _, obj, refill = background_regions(inputs, state)
region = np.where(np.array(obj), 3, np.where(np.array(refill), 2, np.where(np.array(hull) > 0, 1, 0)))
names = ("outside the hull", "kept hull", "refilled", "object's")
to_local = np.linalg.inv(full.to_world)
span = np.array(full.shape) - 1
plan = integrator.plan(("bg",))
cb = plan.sources.bg
dil = score_dilation(ds.size)
dr.set_flag(dr.JitFlag.SymbolicLoops, False)  # the probe runs once an iteration, on evaluated arrays
totals = {k: np.zeros(4) for k in ("metal", "wood", "all")}
counts = {k: 0 for k in totals}
for v in views:
    cam = ds.cameras[v]
    hole = dilate(ds.masks[v], dil)
    rgb = np.clip(ds.as_photographed(render_camera(integrator, cam, ("bg",))["bg"]), 0, 1)
    py, px = np.nonzero(hole)
    o, d = pixel_rays(cam, px + 0.5, py + 0.5)
    med, hit = median_points(integrator, o, d, layer="bg")
    reach = np.where(hit, 0.9 * np.linalg.norm(med - o, axis=1), 0.0)
    samples = []

    def probe(p, w, active, _depth):
        samples.append((np.array(p), np.array(w[cb]), np.array(active)))

    with dr.suspend_grad():
        rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d))
        march.forward(plan, rays, dr.full(mi.Float, 0.5, len(o)), probe=probe)
    share = np.zeros((len(o), 4))
    for p, w, active in samples:
        p = p.T if p.shape[0] == 3 else p
        world = np.array(plan.space.to_world_np(p)) if hasattr(plan.space, "to_world_np") else p
        front = active & (np.linalg.norm(world - o, axis=1) < reach)
        local = p @ to_local[:3, :3].T + to_local[:3, 3]
        ijk = np.clip(np.rint(local * span), 0, span).astype(np.uint32)
        idx = np.array(full.layout.address(mi.UInt32(ijk[:, 0]), mi.UInt32(ijk[:, 1]), mi.UInt32(ijk[:, 2]),
                                           mi.Bool(front)))
        np.add.at(share, (np.arange(len(o)), region[np.where(front, idx, 0)]), np.where(front, w, 0.0))
    c = rgb[py, px]
    kinds = {"metal": (c[:, 2] >= c[:, 0]) & hit, "wood": (c[:, 0] > c[:, 2] + 0.03) & (c[:, 0] > c[:, 1]) & hit,
             "all": hit}
    line = []
    for k, sel in kinds.items():
        totals[k] += share[sel].sum(0)
        counts[k] += int(sel.sum())
        line.append(f"{k} ({sel.sum()}): " + " ".join(f"{x:.3f}" for x in share[sel].mean(0)) if sel.any() else k)
    print(f"view {v}: " + " | ".join(line), flush=True)
print("regions: " + ", ".join(names))
for k in totals:
    per_ray = totals[k] / max(counts[k], 1)
    print(f"all views, {k} ({counts[k]} rays): " + ", ".join(f"{n} {x:.3f}" for n, x in zip(names, per_ray))
          + f"; sum {per_ray.sum():.3f}")
