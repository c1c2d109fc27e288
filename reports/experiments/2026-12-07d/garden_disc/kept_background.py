"""What this folder's probes share: a run's `guided` background refitted once as `bench.strategies RUN guided OUT DATA
--refit` does and kept in OUT/state.npz (later calls load it), and the regions of the background's start that hold
scene-space points (outside the visual hull, a kept hull vertex, a refilled one, the object's own)."""
import os
import shutil
import sys

import mitsuba as mi
import numpy as np

import mi_voldis  # noqa: F401

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "2026-11-30b"))
from probe_run import load_run  # noqa: E402

from mi_voldis.bench.strategies import refit_config  # noqa: E402
from mi_voldis.fit.background import background_regions  # noqa: E402
from mi_voldis.fit.fields import fit_integrator  # noqa: E402
from mi_voldis.fit.state import FitState  # noqa: E402
from mi_voldis.fit.train import fit  # noqa: E402
from mi_voldis.optim.adam import Adam  # noqa: E402

REGIONS = ("outside the hull", "kept hull", "refilled", "object's")


def kept_background(run, out, data):
    """(dataset, fit inputs, state, integrator) of ``run`` read with the dataset copy ``data``, its background
    refitted into ``out``/state.npz the first time and loaded from there after."""
    cfg = refit_config(run, "guided")
    _, ds, _, _ = load_run(run, data)
    kept = os.path.join(out, "state.npz")
    if not os.path.exists(kept):
        state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, cfg.adam_beta1, cfg.adam_beta2))
        state.fields.pop("bg", None)
        state.hull_points = state.prior = state.prior_keys = state.occupancy = None
        state.adam.reset()
        work = os.path.join(out, "work.npz")
        if os.path.lexists(work):
            raise SystemExit(f"error: {work} exists and is not this probe's state; give another OUT")
        state.save(work, "bg", 0)
        fit(ds, work, cfg, resume=True, progress=False)
        shutil.move(work, kept)
    inputs, state = fit(ds, kept, cfg, resume=True, progress=False)
    return ds, inputs, state, fit_integrator(inputs, state)


def region_lookup(inputs, state):
    """A function from scene-space points (n, 3) (and an optional Bool mask of them) to the index in :data:`REGIONS`
    of the stored vertex of the full field nearest each."""
    full = state.fields["full"]
    hull, _, obj, refill = background_regions(inputs, state)
    region = np.where(np.array(obj), 3, np.where(np.array(refill), 2, np.where(np.array(hull) > 0, 1, 0)))
    to_local = np.linalg.inv(full.to_world)
    span = np.array(full.shape) - 1

    def lookup(points, active=None):
        active = np.ones(len(points), bool) if active is None else active
        local = points @ to_local[:3, :3].T + to_local[:3, 3]
        ijk = np.clip(np.rint(local * span), 0, span).astype(np.uint32)
        idx = np.array(full.layout.address(mi.UInt32(ijk[:, 0]), mi.UInt32(ijk[:, 1]), mi.UInt32(ijk[:, 2]),
                                           mi.Bool(active)))
        return region[np.where(active, idx, 0)]

    return lookup


def region_weights(integrator, lookup, o, d, keep=None):
    """Per ray (``o``, ``d``: NumPy (n, 3) world origins and unit directions) the weight of the integrator's
    background layer by region (n, len(:data:`REGIONS`)): each sample of its march put in the region ``lookup``
    (:func:`region_lookup`) gives the nearest stored vertex. ``keep(world points (n, 3), active Bools)``: the
    samples counted (default: every active one)."""
    import drjit as dr

    from mi_voldis.device import from_numpy
    from mi_voldis.render import march
    plan = integrator.plan(("bg",))
    cb = plan.sources.bg
    dr.set_flag(dr.JitFlag.SymbolicLoops, False)  # the probe runs once an iteration, on evaluated arrays
    samples = []

    def probe(p, w, active, _depth):
        samples.append((np.array(p), np.array(w[cb]), np.array(active)))

    with dr.suspend_grad():
        rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d))
        march.forward(plan, rays, dr.full(mi.Float, 0.5, len(o)), probe=probe)
    share = np.zeros((len(o), len(REGIONS)))
    for p, w, active in samples:
        p = p.T if p.shape[0] == 3 else p
        counted = active if keep is None else keep(np.array(plan.space.to_world_np(p)), active)
        np.add.at(share, (np.arange(len(o)), lookup(p, counted)), np.where(counted, w, 0.0))
    return share
