"""Where the foreground misses the object (#46, coverage IoU).

For a removal-family run fitted with --keep-checkpoints: in the first held-out view, the pixels the truth
covers and the foreground does not ("missed") against those it finds; how far behind the full field's
surface the background's lies there; how `background_regions` labels the full-field vertices just behind
that surface (the object's, refilled, or kept as seen by some view); and which training views have those
points in view outside their masks, with the full field's depth there over the point's distance.

    python reports/experiments/2026-11-27/coverage/band.py out/fam_split/runs/family18_0
"""
import json
import os
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")

from mi_voldis.cameras import pixel_of, pixel_rays  # noqa: E402
from mi_voldis.data import load_dataset  # noqa: E402
from mi_voldis.fit.background import background_regions, voxel_of  # noqa: E402
from mi_voldis.fit.config import FitConfig  # noqa: E402
from mi_voldis.fit.fields import FitInputs, fit_integrator  # noqa: E402
from mi_voldis.fit.lift import training_depths  # noqa: E402
from mi_voldis.fit.state import FitState  # noqa: E402
from mi_voldis.metrics import dilate  # noqa: E402
from mi_voldis.optim.adam import Adam  # noqa: E402
from mi_voldis.render.views import render_camera  # noqa: E402


def vertex_index(field, space, points):
    """Stored index of the lattice vertex nearest to each world point (n, 3)."""
    lay, inv = field.layout, np.linalg.inv(field.to_world)
    local = space.from_world_np(points) @ inv[:3, :3].T + inv[:3, 3]
    top = np.array(field.shape) - 1
    i, j, k = np.clip(np.round(local * top).astype(int), 0, top).T
    s, b = lay.shift, lay.brick
    slot = lay.table[k >> s, j >> s, i >> s].astype(np.int64)
    return slot * b ** 3 + ((k & (b - 1)) * b + (j & (b - 1))) * b + (i & (b - 1))


def main(run):
    with open(os.path.join(run, "config.json")) as f:
        record = json.load(f)["dataset"]
    cfg = FitConfig.from_sources(os.path.join(run, "config.json"), [])
    ds = load_dataset(record["path"], record["format"], record["holdout"])
    state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}))
    inputs = FitInputs.of(ds, cfg, os.devnull, progress=False)
    hull, _, obj, refill = background_regions(inputs, state)
    hull, obj, refill = np.array(hull) > 0, np.array(obj), np.array(refill)
    full = state.fields["full"]
    v = ds.test[0]
    out = render_camera(fit_integrator(inputs, state), ds.cameras[v], ("full", "bg", "fg"))
    truth, found = ds.coverage[v] > 0.5, out["fg_coverage"] > 0.5
    voxel = voxel_of(full)
    for name, sel in (("missed", truth & ~found), ("found", truth & found)):
        gap = out["bg"][2][sel] - out["full"][2][sel]
        print(f"{name}: {int(sel.sum())} pixels, background surface behind the full one by "
              f"{np.nanmedian(gap) / voxel:.1f} voxels (median)")
        py, px = np.nonzero(sel)
        o, d = pixel_rays(ds.cameras[v], px + 0.5, py + 0.5)
        for behind in (0.5, 1.5, 3.0):
            idx = vertex_index(full, inputs.space, o + (out["full"][2][py, px, None] + behind * voxel) * d)
            print(f"  {behind} voxels behind: the object's {obj[idx].mean():.2f}, refilled {refill[idx].mean():.2f}, "
                  f"kept as seen {(hull[idx] & ~refill[idx]).mean():.2f}")
    py, px = np.nonzero(truth & ~found)
    o, d = pixel_rays(ds.cameras[v], px + 0.5, py + 0.5)
    points = o + (out["full"][2][py, px, None] + 0.5 * voxel) * d
    depth = training_depths(inputs, state, median=True)
    for u in depth:
        cam = ds.cameras[u]
        ix, iy, ok = pixel_of(cam, points)
        masked = np.zeros(len(points), bool)
        masked[ok] = dilate(ds.masks[u], 1)[iy[ok], ix[ok]]
        dist = np.linalg.norm(points - cam.to_world[:3, 3], axis=1)
        there = np.full(len(points), np.nan)
        there[ok] = depth[u][iy[ok], ix[ok]]
        in_view = ok & ~masked & ~(there < 0.95 * dist)
        if in_view.mean() > 0.05:
            print(f"training view {u}: {in_view.mean():.2f} of the missed points in view unmasked, full-field depth "
                  f"there / distance {np.nanmedian((there / dist)[in_view]):.3f}")


if __name__ == "__main__":
    main(sys.argv[1])
