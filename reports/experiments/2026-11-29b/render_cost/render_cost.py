"""#42: a fitted run's held-out views rendered with render-time settings only (no refit): the occupancy
cells (voxels of the full grid across; the fit's are 4) and the early termination's transmittance.
Prints held-out PSNR, the background's in-mask PSNR where the dataset has ground truth, evaluated samples
a ray and the seconds the renders took (rows alternate, best of REPEATS).

    python reports/experiments/2026-11-29b/render_cost/render_cost.py RUN CELLS:TRANSMITTANCE ... [--repeats N]
    e.g. RUN 4:1e-4 2:1e-4 4:1e-3 2:1e-3
"""
import sys
import time

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
import drjit as dr  # noqa: E402

from mi_voldis.cameras import pixel_rays  # noqa: E402
from mi_voldis.device import from_numpy  # noqa: E402
from mi_voldis.metrics import dilate, psnr, score_dilation  # noqa: E402
from mi_voldis.render import quadrature  # noqa: E402
from mi_voldis.render.rays import render_rays  # noqa: E402
from mi_voldis.tasks.base import FittedRun  # noqa: E402


def render(integrator, cam):
    """{'full', 'bg': (rgb, alpha)} at the pixel centres, and the evaluated samples of each ray."""
    py, px = np.mgrid[0:cam.height, 0:cam.width]
    o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
    parts = {"full": ([], []), "bg": ([], [])}
    ev = []
    with dr.suspend_grad():
        for s in range(0, len(o), 1 << 16):
            n = min(1 << 16, len(o) - s)
            res = render_rays(integrator, from_numpy(mi.Point3f, o[s:s + n]), from_numpy(mi.Vector3f, d[s:s + n]),
                              dr.full(mi.Float, 0.5, n), ("full", "bg"))
            for layer in parts:
                parts[layer][0].append(np.array(res[layer][0]).T)
                parts[layer][1].append(np.array(res[layer][1]))
            ev.append(np.array(res["evaluated"]))
    h, w = cam.height, cam.width
    return {k: (np.concatenate(v[0]).reshape(h, w, 3), np.concatenate(v[1]).reshape(h, w)) for k, v in parts.items()}, \
        np.concatenate(ev)


args = [a for a in sys.argv[1:] if not a.startswith("--")]
repeats = int(sys.argv[sys.argv.index("--repeats") + 1]) if "--repeats" in sys.argv else 2
if "--repeats" in sys.argv:
    args.remove(str(repeats))
run = FittedRun(args[0])
ds = run.dataset
res = max(run.fields["full"].shape)
rows = [(int(c), float(t)) for c, t in (a.split(":") for a in args[1:])]
integ = {c: run.integrator(occupancy_resolution=int(np.ceil((res - 1) / c))) for c in {c for c, _ in rows}}
best = {}
for rep in range(repeats):
    for cells, trans in rows:
        quadrature.OPTICAL_DEPTH_CUTOFF = float(-np.log(trans))
        t0 = time.perf_counter()
        out = {v: render(integ[cells], ds.cameras[v]) for v in ds.test}
        sec = time.perf_counter() - t0
        best[(cells, trans)] = min(sec, best.get((cells, trans), (np.inf,))[0]), out
dil = score_dilation(ds.size)
for cells, trans in rows:
    sec, out = best[(cells, trans)]
    ev = np.concatenate([out[v][1] for v in ds.test])
    out = {v: out[v][0] for v in ds.test}
    full = [psnr(np.clip(ds.as_photographed(out[v]["full"]), 0, 1), ds.images[v]) for v in ds.test]
    line = f"cells {cells} voxels, transmittance {trans:g}: held out {np.mean(full):.4f} dB"
    if ds.backgrounds is not None:
        bg = [psnr(np.clip(ds.as_photographed(out[v]["bg"]), 0, 1), ds.backgrounds[v], dilate(ds.masks[v], dil))
              for v in ds.test]
        line += f", background in the mask {np.mean(bg):.4f} dB"
    print(f"{line}; evaluated samples a ray {ev.mean():.1f} (p90 {np.percentile(ev, 90):.0f}); {sec:.2f} s for "
          f"{len(ds.test)} views (full + bg layers)", flush=True)
