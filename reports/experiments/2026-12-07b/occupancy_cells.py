"""Training steps of a fitted run's full field under fitting's rules (rays stopped at transmittance 1e-4,
strides in contracted space, the fitted occupancy threshold) with occupancy cells of C voxels, the cell sizes
timed in alternating blocks in one process on the same rays (``mi_voldis.bench.throughput.interleaved``'s
method: a warm-up step before each block), Adam at a negligible rate so that the field does not move.

    python reports/experiments/2026-12-07b/occupancy_cells.py RUN [CELLS ...]   (default 8 4 2)

A CELLS of the form ``Cflat`` marches without the occupancy's coarsened grid; ``Cold`` also without the runs to
a cell's exit (every empty cell crossed in steps of 0.9 (cell - voxel), as before 2026-12-07).

``ROUNDS`` (environment, default 3): blocks of each variant. Prints, per cell size, the median seconds a step,
the samples a step evaluated and the occupied fraction.
"""
import os
import sys
import time

import drjit as dr
import mitsuba as mi
import numpy as np

sys.path.insert(0, os.getcwd())
mi.set_variant("llvm_ad_rgb")
from mi_voldis import load_run  # noqa: E402
from mi_voldis.optim.adam import Adam  # noqa: E402
from mi_voldis.optim.parameters import PackedParameters  # noqa: E402
from mi_voldis.raybank import RayBank  # noqa: E402
from mi_voldis.render import march  # noqa: E402
from mi_voldis.render.rays import render_rays  # noqa: E402

BATCH, BLOCK = 8192, 6
ROUNDS = int(os.environ.get("ROUNDS", 3))  # blocks of each variant, alternating

if len(sys.argv) < 2:
    sys.exit("occupancy_cells.py: give a fitted run's folder")
run = load_run(sys.argv[1])
cells = sys.argv[2:] or ["8", "4", "2"]
ds = run.dataset
bank = RayBank(ds, ds.train)
rng = np.random.default_rng(0)
batches = [bank.batch(rng, BATCH) for _ in range(BLOCK + 1)]

def old_skip(self, xc, occupied, step):
    """The step across an empty cell before 2026-12-07: 0.9 (cell - voxel) from wherever the ray is."""
    return dr.select(occupied, step, self.plan.skip)


new_skip = march.Path.skip
steps = {}
for c in cells:
    resolution = max(run.integrator().fields["full"].shape)
    cells_across = int(np.ceil((resolution - 1) / int(c.removesuffix("flat").removesuffix("old"))))
    integ = run.integrator(occupancy_resolution=cells_across, stop_transmittance=1e-4)
    if c.endswith("flat") or c.endswith("old"):
        integ.coarse_skip = lambda: ()
        integ._plans.clear()
    params = PackedParameters({"full": integ.fields["full"]})
    adam = Adam({key: 1e-12 for key in params})

    def step(batch, integ=integ, params=params, adam=adam, old=c.endswith("old")):
        march.Path.skip = old_skip if old else new_skip  # read when the step's loops are traced
        o, d, color, *_ = batch
        for key in params:
            dr.enable_grad(params[key])
        params.update()
        u = dr.full(mi.Float, 0.5, dr.width(o))
        out = render_rays(integ, o, d, u, layers=("full",), distortion=("full",))
        loss = dr.mean(dr.square(out["full"][0] - color)) + 1e-2 * dr.mean(out["distortion"]["full"])
        dr.backward(loss)
        adam.step(params, {key: dr.grad(params[key]) for key in params})
        params.update()
        dr.eval([params[key] for key in params])
        return float(dr.sum(out["evaluated"])[0])

    steps[c] = (step, integ.occupancy.fraction)

times = {c: [] for c in cells}
samples = {c: [] for c in cells}
for _ in range(ROUNDS):
    for c in cells:
        step = steps[c][0]
        step(batches[0])  # warm-up
        for b in batches[1:]:
            t0 = time.perf_counter()
            samples[c].append(step(b))
            times[c].append(time.perf_counter() - t0)
base = np.median(times[cells[0]])
for c in cells:
    t = np.median(times[c])
    print(f"cells of {c} voxels: {t * 1e3:.1f} ms a step ({t / base:.3f} x cells of {cells[0]}), "
          f"{np.mean(samples[c]) / 1e3:.0f} k samples a step, occupied {steps[c][1]:.3f}")
