"""Where the full field's and the background's weights lie along four rays through the mask of held-out view V."""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np
from kept_run import run_integrator

import mi_voldis  # noqa
from mi_voldis.cameras import pixel_rays
from mi_voldis.device import from_numpy
from mi_voldis.render import march
from mi_voldis.render.surface import median_depth

run = sys.argv[1]
v = int(sys.argv[2])
ds, integ = run_integrator(run)
cam = ds.cameras[v]
m = ds.masks[v]
ys, xs = np.nonzero(m)
print("mask bbox", ys.min(), ys.max(), xs.min(), xs.max(), "image", m.shape)
dfull, hf = median_depth(integ, cam, layer="full")
dbg, hb = median_depth(integ, cam, layer="bg")
pix = [(int(np.percentile(ys, q)), int(np.median(xs[ys == int(np.percentile(ys, q))]))) for q in (10, 30, 50, 70)]
for layer in ("full", "bg"):
    plan = integ.plan((layer,))
    chain = getattr(plan.sources, layer)
    py = np.array([p[0] for p in pix])
    px = np.array([p[1] for p in pix])
    o, d = pixel_rays(cam, px + 0.5, py + 0.5)
    n = len(o)
    rec_t, rec_w = [], []
    T = dr.zeros(mi.Float, n * 4096)
    W = dr.zeros(mi.Float, n * 4096)
    cnt = dr.zeros(mi.UInt32, n)
    idx = dr.arange(mi.UInt32, n)
    samples = []

    def probe(p, w, active, depth):
        q = plan.space.to_world(p)
        samples.append((q, w[chain], active))

    rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d))
    # record per-sample via scatter into python lists (small n): evaluate in the loop
    dist_w = [[] for _ in range(n)]

    def probe2(p, w, active, depth):
        q = plan.space.to_world(p)
        dist = dr.norm(q - from_numpy(mi.Point3f, o))
        k = dr.scatter_inc(cnt, idx, active)
        dr.scatter(T, dist, idx * 4096 + k, active & (k < 4096))
        dr.scatter(W, w[chain], idx * 4096 + k, active & (k < 4096))

    march.forward(plan, rays, dr.full(mi.Float, 0.5, n), probe=probe2)
    T_ = np.array(T).reshape(n, 4096)
    W_ = np.array(W).reshape(n, 4096)
    c = np.array(cnt)
    for r in range(n):
        t, w = T_[r, : c[r]], W_[r, : c[r]]
        order = np.argsort(t)
        t, w = t[order], w[order]
        cw = np.cumsum(w)
        qs = [t[np.searchsorted(cw, f * cw[-1])] if cw[-1] > 0 else np.nan for f in (0.1, 0.25, 0.5, 0.75, 0.9)]
        print(
            layer,
            pix[r],
            "total w %.2f" % cw[-1],
            "w-quantile depths",
            np.round(qs, 2),
            "median depth full %.2f bg %.2f" % (dfull[pix[r]], dbg[pix[r]]),
        )
