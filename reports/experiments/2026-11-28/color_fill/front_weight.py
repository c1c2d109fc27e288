"""How much of the background's weight stands in front of the surface the object hides: on the masked rays
of a run's first held-out views, the share of the background layer's weight whose sample's nearest vertex
lies more than 10% nearer than that view's hidden depth (its full-field median depth around the mask filled
in as disparity, ``mi_voldis.fit.visibility.hidden_depth``), and the full field's for comparison.

    python reports/experiments/2026-11-28/color_fill/front_weight.py RUN [VIEWS] [--set KEY=VALUE ...]

RUN: a fit kept with --keep-checkpoints. Without --set its own background is read; with settings it is
refitted with them first (in a temporary folder). VIEWS: how many held-out views (default 2).
"""
import sys

import numpy as np
from refitted import refitted, split_sets


def main(argv):
    sets, plain = split_sets(argv)
    if not 1 <= len(plain) <= 2 or (len(plain) == 2 and not plain[1].isdigit()):
        raise SystemExit(__doc__.strip().splitlines()[5].strip())
    run, count = plain[0], int(plain[1]) if len(plain) == 2 else 2
    import drjit as dr
    import mitsuba as mi

    from mi_voldis.cameras import pixel_of, pixel_rays
    from mi_voldis.device import from_numpy
    from mi_voldis.field_state import vertex_positions
    from mi_voldis.fit.visibility import hidden_depth
    from mi_voldis.metrics import dilate
    from mi_voldis.render import march
    from mi_voldis.render.surface import median_depth
    ds, cfg, inputs, state, integrator = refitted(run, sets, refit=bool(sets))
    full = state.fields["full"]
    pts, real = vertex_positions(full)
    world = inputs.space.to_world_np(pts)
    origin = mi.Point3f(*(float(x) for x in full.to_world[:3, 3]))
    scale = mi.Vector3f(*(float(x) for x in (np.array(full.shape) - 1) / np.diag(full.to_world)[:3]))
    top = [int(n) - 1 for n in full.shape]
    for v in list(ds.test)[:count]:
        cam = ds.cameras[v]
        depth, hit = median_depth(integrator, cam)
        filled = hidden_depth(cam, np.where(hit, depth, np.nan), ds.masks[v], dilate(ds.masks[v], 2))
        if filled is None:
            continue
        ix, iy, ok = pixel_of(cam, world)
        ok &= real
        front = np.zeros(len(world), bool)
        near = np.linalg.norm(world - cam.to_world[:3, 3], axis=1)
        front[ok] = near[ok] < 0.9 * filled[iy[ok], ix[ok]]  # NaN (no hidden depth) compares False
        front_d = mi.Bool(front)
        py, px = np.nonzero(ds.masks[v])
        o, d = pixel_rays(cam, px + 0.5, py + 0.5)
        shares = {}
        for layer in ("bg", "full"):
            plan = integrator.plan((layer,))
            chain = getattr(plan.sources, layer)
            ahead, total = dr.zeros(mi.Float, len(o)), dr.zeros(mi.Float, len(o))

            def probe(p, w, active, _):
                idx = [mi.UInt32(dr.clip(mi.Int32(dr.round(c)), 0, t)) for c, t in zip((p - origin) * scale, top)]
                ray = dr.arange(mi.UInt32, dr.width(p))
                hit_front = dr.gather(mi.Bool, front_d, full.layout.address(*idx, active), active)
                dr.scatter_add(total, w[chain], ray, active)
                dr.scatter_add(ahead, w[chain], ray, active & hit_front)
            rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d))
            with dr.suspend_grad():
                march.forward(plan, rays, dr.full(mi.Float, 0.5, len(o)), probe=probe)
            shares[layer] = (float(dr.mean(ahead)[0]), float(dr.mean(total)[0]))
        print(f"view {v}: weight in front of the hidden surface, mean over masked rays: background "
              f"{shares['bg'][0]:.3f} of {shares['bg'][1]:.3f}, full field {shares['full'][0]:.3f} of "
              f"{shares['full'][1]:.3f}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
