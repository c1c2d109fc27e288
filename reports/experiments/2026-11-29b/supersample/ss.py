"""Held-out PSNR of a fitted run rendered at pixel centres against k x k stratified positions inside each
pixel (box filter, as the fit's rays are placed), the ray offsets stratified too.
usage: python ss.py RUN [K ...]"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

import mi_voldis
from mi_voldis.cameras import pixel_rays
from mi_voldis.device import from_numpy
from mi_voldis.metrics import psnr, ssim
from mi_voldis.render.rays import render_rays

run = mi_voldis.load_run(sys.argv[1])
ds, integ = run.dataset, run.integrator()
ks = [int(k) for k in sys.argv[2:]] or [1, 2, 3]


def render(cam, k):
    py, px = np.mgrid[0:cam.height, 0:cam.width]
    acc = 0.0
    for a in range(k):
        for b in range(k):
            o, d = pixel_rays(cam, px.ravel() + (b + 0.5) / k, py.ravel() + (a + 0.5) / k)
            u = ((a * k + b) + 0.5) / (k * k)  # along the ray: stratified too
            rgb, al = [], []
            with dr.suspend_grad():
                for s in range(0, len(o), 1 << 16):
                    oo, dd = from_numpy(mi.Point3f, o[s:s + 65536]), from_numpy(mi.Vector3f, d[s:s + 65536])
                    res = render_rays(integ, oo, dd, dr.full(mi.Float, u, dr.width(oo)), ("full",), None)
                    rgb.append(np.array(res["full"][0]).T)
                    al.append(np.array(res["full"][1]))
            acc = acc + np.concatenate([np.concatenate(rgb), np.concatenate(al)[:, None]], 1)
    acc = (acc / (k * k)).reshape(cam.height, cam.width, 4)
    return acc[..., :3], acc[..., 3]


for k in ks:
    ps, ss = [], []
    for v in ds.test:
        img = np.clip(ds.as_photographed(render(ds.cameras[v], k)), 0, 1)
        ps.append(psnr(img, ds.images[v]))
        ss.append(ssim(img, ds.images[v]))
    print(f"k={k}: PSNR {np.mean(ps):.3f} ({', '.join(f'{p:.2f}' for p in ps)}), SSIM {np.mean(ss):.4f}", flush=True)
