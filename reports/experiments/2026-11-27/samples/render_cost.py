"""#42: evaluated samples per ray against held-out PSNR of a fitted run, at render time: the early
termination's optical-depth cutoff, the occupancy threshold (times the run's) and the step (times the run's).

    python reports/experiments/2026-11-27/samples/render_cost.py RUN CUTOFFS OCCUPANCY_FACTORS [STEP_FACTORS]
    e.g. RUN 9.2103,4.6052 1          (transmittance 1e-4, 1e-2)
         RUN 9.2103 3,10,30,100
         RUN 9.2103 1000 1.5,2
"""
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
import drjit as dr  # noqa: E402

from mi_voldis.cameras import pixel_rays  # noqa: E402
from mi_voldis.device import from_numpy  # noqa: E402
from mi_voldis.metrics import psnr  # noqa: E402
from mi_voldis.render import quadrature  # noqa: E402
from mi_voldis.render.rays import render_rays  # noqa: E402
from mi_voldis.tasks.base import FittedRun  # noqa: E402


def view(integrator, ds, v):
    """Held-out view ``v`` of ``ds`` rendered: its PSNR, evaluated samples per pixel and the image."""
    cam = ds.cameras[v]
    py, px = np.mgrid[0:cam.height, 0:cam.width]
    o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
    rgb, ev = [], []
    with dr.suspend_grad():
        for s in range(0, len(o), 1 << 17):
            res = render_rays(integrator, from_numpy(mi.Point3f, o[s:s + (1 << 17)]),
                              from_numpy(mi.Vector3f, d[s:s + (1 << 17)]),
                              dr.full(mi.Float, 0.5, min(1 << 17, len(o) - s)), ("full",))
            rgb.append(np.array(res["full"][0]).T)
            ev.append(np.array(res["evaluated"]))
    img = np.clip(np.concatenate(rgb).reshape(cam.height, cam.width, 3), 0, 1)
    ev = np.concatenate(ev)
    return psnr(img, ds.images[v]), ev, img


def main():
    run = FittedRun(sys.argv[1])
    ds = run.dataset
    occ0 = run.properties["occupancy_threshold"]
    print("properties", {k: v for k, v in run.properties.items() if not hasattr(v, "shape")})

    for cutoff in [float(a) for a in sys.argv[2].split(",")]:
        for occ in [float(a) for a in sys.argv[3].split(",")]:
            quadrature.OPTICAL_DEPTH_CUTOFF = cutoff
            integ = run.integrator(occupancy_threshold=occ0 * occ)
            ps, evs = zip(*[view(integ, ds, v)[:2] for v in ds.test])
            ev = np.concatenate(evs)
            print(f"cutoff {cutoff:.2f} occ x{occ:g}: psnr {np.mean(ps):.3f} evaluated mean {ev.mean():.1f} "
                  f"p50 {np.percentile(ev, 50):.0f} p90 {np.percentile(ev, 90):.0f} max {ev.max():.0f}", flush=True)

    if len(sys.argv) > 4:
        quadrature.OPTICAL_DEPTH_CUTOFF = 9.2103
        for k in [float(a) for a in sys.argv[4].split(",")]:
            integ = run.integrator(step_size=run.properties["step_size"] * k)
            ps, evs = zip(*[view(integ, ds, v)[:2] for v in ds.test])
            ev = np.concatenate(evs)
            print(f"step x{k:g}: psnr {np.mean(ps):.3f} evaluated mean {ev.mean():.1f} p50 {np.percentile(ev, 50):.0f}",
                  flush=True)


if __name__ == "__main__":
    main()
