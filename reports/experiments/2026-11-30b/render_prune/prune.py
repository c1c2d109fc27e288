"""#42: a fitted run's held-out views rendered with render-time occupancy settings only (no refit): the
occupancy threshold (a multiple of the fit's), the cells (voxels of the full grid across; the fit's are 4) and
the early termination's transmittance. Prints, per setting, held-out PSNR against the photographs, PSNR of the
full layer against the fit's own settings' render (fidelity), the background's in-mask change where the run
has masks, and evaluated samples a ray.

    python prune.py RUN [--views N] MULT:CELLS:TRANSMITTANCE ...
    e.g. prune.py RUN 1:4:1e-4 3:4:1e-4 10:2:1e-3
"""
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
import drjit as dr  # noqa: E402

from mi_voldis.cameras import pixel_rays  # noqa: E402
from mi_voldis.data.types import spread  # noqa: E402
from mi_voldis.device import from_numpy  # noqa: E402
from mi_voldis.metrics import psnr  # noqa: E402
from mi_voldis.render.rays import render_rays  # noqa: E402
from mi_voldis.render.views import render_camera  # noqa: E402
from mi_voldis.tasks.base import FittedRun  # noqa: E402


def render(integrator, cam):
    out = render_camera(integrator, cam, ("full", "bg"))
    return out, _evaluated(integrator, cam)


def _evaluated(integrator, cam):
    """Evaluated samples of every pixel-centre ray of ``cam`` (a statistic render_camera does not return)."""
    ys, xs = np.divmod(np.arange(cam.width * cam.height), cam.width)
    o, d = pixel_rays(cam, xs + 0.5, ys + 0.5)
    chunks = np.array_split(np.arange(len(o)), max(1, len(o) >> 16))
    with dr.suspend_grad():
        counts = [render_rays(integrator, from_numpy(mi.Point3f, o[c]), from_numpy(mi.Vector3f, d[c]),
                              dr.full(mi.Float, 0.5, len(c)), ("full", "bg"))["evaluated"] for c in chunks]
        return np.concatenate([np.array(n) for n in counts])


args = sys.argv[1:]
nviews = None
if "--views" in args:
    i = args.index("--views")
    nviews = int(args[i + 1])
    del args[i:i + 2]
run = FittedRun(args[0])
ds = run.dataset
tests = list(ds.test)
if nviews and len(tests) > nviews:
    tests = [tests[i] for i in spread(len(tests), nviews)]
res = max(run.fields["full"].shape)
base_thr = run.properties["occupancy_threshold"]
base_cells = int(round((res - 1) / max(run.properties["occupancy_resolution"], 1)))
print(f"{args[0]}: grid {res}, fit's occupancy {run.properties['occupancy_resolution']} cells "
      f"(~{base_cells} voxels), threshold {base_thr:.4g}; views {tests}", flush=True)
ref = None
for spec in args[1:]:
    mult, cells, trans = spec.split(":")
    mult, cells, trans = float(mult), int(cells), float(trans)
    integ = run.integrator(occupancy_resolution=int(np.ceil((res - 1) / cells)), occupancy_threshold=base_thr * mult,
                           stop_transmittance=trans)
    out = {v: render(integ, ds.cameras[v]) for v in tests}
    if ref is None:
        ref = out
    ev = np.concatenate([out[v][1] for v in tests])
    full = np.mean([psnr(np.clip(ds.as_photographed(out[v][0]["full"]), 0, 1), ds.images[v]) for v in tests])
    fid = np.mean([psnr(np.clip(out[v][0]["full"][0], 0, 1), np.clip(ref[v][0]["full"][0], 0, 1)) for v in tests])
    fidbg = np.mean([psnr(np.clip(out[v][0]["bg"][0], 0, 1), np.clip(ref[v][0]["bg"][0], 0, 1)) for v in tests])
    print(f"threshold x{mult:g} cells {cells} stop {trans:g}: held out {full:.4f} dB, fidelity full {fid:.1f} "
          f"bg {fidbg:.1f} dB, samples a ray {ev.mean():.1f} (p90 {np.percentile(ev, 90):.0f}), "
          f"occupied {integ.occupancy.fraction:.3f}", flush=True)
