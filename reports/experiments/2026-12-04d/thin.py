"""#42 trial: contracted rays take longer steps through thin occupied cells (render only, no refit).

The run rendered with today's scene rule (occupancy cells of one voxel, rays stopped at transmittance 1e-3,
whatever its scene.xml says); cells of the fit's full grid are empty (below the scene's threshold, skipped),
thin (below MULT x that threshold on a grid of CELLS-voxel cells) or dense. In a thin cell a ray steps
min(STEP x the scene step, 0.9 (cell - reach)), so it cannot step past the margin the dilation leaves around
dense density. Prints held-out PSNR, fidelity to the scene's own render and evaluated samples a ray per setting.

    python thin.py RUN [--views N] scene MULT:CELLS:STEP[,MULT:CELLS:STEP...] ...   (levels: lowest threshold first)
"""
import dataclasses
import sys

import drjit as dr
import numpy as np
from common import fitted_run

from mi_voldis.metrics import psnr
from mi_voldis.render.occupancy import Occupancy
from mi_voldis.render.views import render_camera

run, ds, tests, res, specs = fitted_run(sys.argv[1:])
props = run.properties
print(f"{sys.argv[1]}: grid {res}, scene occupancy {props['occupancy_resolution']} cells, threshold "
      f"{props['occupancy_threshold']:.4g}, stop {props.get('stop_transmittance')}, step {props['step_size']:.4g}; "
      f"views {tests}", flush=True)
ref = None
for spec in specs:
    integ = run.integrator(occupancy_resolution=res - 1, stop_transmittance=1e-3)  # today's scene rule
    if spec != "scene":  # MULT:CELLS:STEP[,MULT:CELLS:STEP...], the lowest threshold first
        lookups, sources = integ._lookups()
        dense = [lk for lk in lookups if lk.key != sources.fg_color]
        lo, hi = integ.scene_bounds()
        levels, names = [], []
        for level in spec.split(","):
            mult, cells, stepm = level.split(":")
            mult, cells, stepm = float(mult), int(cells), float(stepm)
            grid = Occupancy.build(dense, integ.space, int(np.ceil((res - 1) / cells)),
                                   props["occupancy_threshold"] * mult, lo, hi)
            level_step = max(min(stepm * integ.step_size, 0.9 * (grid.cell_size - grid.reach)), integ.step_size)
            levels.append((grid, level_step))
            names.append(f"below x{mult:g} on {cells}-voxel cells step {level_step / integ.step_size:.2f}x")
        orig = integ.plan

        def plan(*a, _orig=orig, _levels=tuple(levels), **k):
            return dataclasses.replace(_orig(*a, **k), thin=_levels)
        integ.plan = plan
        label = "; ".join(names)
    else:
        label = "scene rule"
    with dr.suspend_grad():
        out = {v: render_camera(integ, ds.cameras[v], ("full", "bg")) for v in tests}
    if ref is None:
        ref = out
    ev = np.concatenate([out[v]["evaluated"].ravel() for v in tests])
    full = np.mean([psnr(np.clip(ds.as_photographed(out[v]["full"]), 0, 1), ds.images[v]) for v in tests])
    fid = np.mean([psnr(np.clip(out[v]["full"][0], 0, 1), np.clip(ref[v]["full"][0], 0, 1)) for v in tests])
    print(f"{label}: held out {full:.4f} dB, fidelity {fid:.1f} dB, samples a ray {ev.mean():.1f} "
          f"(p90 {np.percentile(ev, 90):.0f})", flush=True)
