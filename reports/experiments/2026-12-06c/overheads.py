"""The full phase's costs outside its steps, before and after this session's changes, side by side in one
process on a fitted run (alternating, ROUNDS each, the median): a checkpoint of three packed arrays of the
run's size (the field, Adam's two moments) written from NumPy copies (before) or views of Dr.Jit's buffers
(after); the log's evaluation, the first `eval_views` (3) held-out views rendered with the run's fitting
integrator at fitting's stop 1e-4 (before) or the fitted scene's 1e-2 (after); and one pass of the moving
average over the packed values (every k-th step in the package).

    python overheads.py RUN SCRATCH_FOLDER
"""
import os
import sys
import time

import drjit as dr
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-12-04d"))
from common import fitted_run  # noqa: E402  (2026-12-04d's: the run and its held-out views; selects the variant)

from mi_voldis.io.run_folder import Checkpoint  # noqa: E402
from mi_voldis.optim.average import moving_average  # noqa: E402
from mi_voldis.render.views import render_camera  # noqa: E402

ROUNDS = 3
run, ds, tests, res, rest = fitted_run(sys.argv[1:2])
scratch = sys.argv[2]
os.makedirs(scratch, exist_ok=False)
data = run.fields["full"].packed
arrays = [data, data * 0.5, data * 0.25]
dr.eval(*arrays)
path = os.path.join(scratch, "last.npz")


def timed(fn):
    dr.sync_thread()
    t = time.perf_counter()
    fn()
    dr.sync_thread()
    return time.perf_counter() - t


def save(convert):
    Checkpoint(path).save({f"a{k}": convert(a) for k, a in enumerate(arrays)}, {"step": 0})


integ = run.integrator(occupancy_resolution=res - 1, stop_transmittance=1e-4)


def log_eval(stop):
    with integ.stopped_at(stop) as i:
        for v in tests[:3]:
            render_camera(i, ds.cameras[v], ("full",))


average = moving_average(None, data, 0.9)
times = {k: [] for k in ("checkpoint, copies", "checkpoint, views", "log, stop 1e-4", "log, stop 1e-2",
                         "moving average, one pass")}
log_eval(1e-4), log_eval(1e-2)  # compiled
for _ in range(ROUNDS):
    times["checkpoint, copies"].append(timed(lambda: save(np.array)))
    times["checkpoint, views"].append(timed(lambda: save(np.asarray)))
    times["log, stop 1e-4"].append(timed(lambda: log_eval(1e-4)))
    times["log, stop 1e-2"].append(timed(lambda: log_eval(1e-2)))
    times["moving average, one pass"].append(timed(lambda: moving_average(average, data, 0.9)))
os.remove(path)
os.rmdir(scratch)
print(f"{sys.argv[1]}: {dr.width(data) / 1e6:.1f} M packed floats; median of {ROUNDS}, alternating")
for k, v in times.items():
    print(f"  {k}: {np.median(v):.3f} s ({', '.join(f'{x:.3f}' for x in v)})")
