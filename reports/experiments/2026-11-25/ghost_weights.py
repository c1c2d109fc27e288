"""Where the default background's weight on the held-out masked pixels lies, by vertex class.

    python reports/experiments/2026-11-25/ghost_weights.py RUN OUT [KEY=VALUE ...]

RUN: a fit kept with --keep-checkpoints. The background is refitted as the strategies command does
(``guided``, settings KEY=VALUE over RUN's), then each held-out masked pixel's ray is marched through
it and every sample's background weight is added to its nearest lattice vertex; the totals are
printed per class of :func:`mi_voldis.fit.background.background_regions` (the object's voxels, the
refilled hull, the seen hull kept with the full field's values, outside the hull).
"""
import json
import os
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

from mi_voldis.bench.strategies import refit_config
from mi_voldis.cameras import pixel_rays
from mi_voldis.data import load_dataset
from mi_voldis.device import from_numpy
from mi_voldis.field_state import vertex_positions
from mi_voldis.fit.background import background_regions
from mi_voldis.fit.fields import fit_integrator
from mi_voldis.fit.state import FitState
from mi_voldis.fit.train import fit
from mi_voldis.optim.adam import Adam
from mi_voldis.render import march


def refitted(run, out, sets):
    cfg = refit_config(run, "guided", sets)
    record = json.load(open(os.path.join(run, "config.json")))["dataset"]
    ds = load_dataset(record["path"], record["format"], record["holdout"])
    os.makedirs(out, exist_ok=True)
    state = FitState.load(os.path.join(run, "checkpoints", "last.npz"),
                          Adam({}, cfg.adam_beta1, cfg.adam_beta2, warmup=cfg.lr_warmup))
    state.fields.pop("bg", None)
    state.hull_points = state.prior = state.prior_keys = state.occupancy = None
    state.adam.reset()
    checkpoint = os.path.join(out, "state.npz")
    state.save(checkpoint, "bg", 0)
    inputs, state = fit(ds, checkpoint, cfg, resume=True, progress=False)
    os.remove(checkpoint)
    return ds, inputs, state


def main(run, out, *sets):
    ds, inputs, state = refitted(run, out, sets)
    hull, _, obj, refill = background_regions(inputs, state)
    bg = state.fields["bg"]
    integrator = fit_integrator(inputs, state)
    plan = integrator.plan(("bg",))
    chain = plan.sources.bg
    weight = dr.zeros(mi.Float, bg.vertices)
    m = bg.to_world
    origin = mi.Point3f(*(float(x) for x in m[:3, 3]))
    scale = mi.Vector3f(*(float(x) for x in (np.array(bg.shape) - 1) / np.diag(m)[:3]))
    top = [int(n) - 1 for n in bg.shape]
    pixels = 0
    with dr.suspend_grad():
        for v in ds.test:
            py, px = np.nonzero(ds.masks[v])
            if not len(px):
                continue
            o, d = pixel_rays(ds.cameras[v], px + 0.5, py + 0.5)
            pixels += len(o)

            def add(p, w, active, depth):
                c = [mi.UInt32(dr.clip(mi.Int32(dr.round(q)), 0, t)) for q, t in zip((p - origin) * scale, top)]
                dr.scatter_add(weight, w[chain], bg.layout.address(c[0], c[1], c[2], active), active)

            rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d))
            march.forward(plan, rays, dr.full(mi.Float, 0.5, len(o)), probe=add)
    w = np.array(weight) / pixels
    h, ob, rf = np.array(hull) > 0, np.array(obj), np.array(refill)
    print(f"weight per held-out masked pixel: {w.sum():.3f}")
    for name, part in [("object's voxels", h & ob), ("refilled hull", h & rf & ~ob), ("seen hull, kept", h & ~rf),
                       ("outside the hull", ~h)]:
        print(f"  {name:18s} {w[part].sum():.3f}")
    pos, _ = vertex_positions(bg)
    np.savez(os.path.join(out, "weights.npz"), weight=w, hull=h, obj=ob, refill=rf, pos=inputs.space.to_world_np(pos))


if __name__ == "__main__":
    main(*sys.argv[1:])
