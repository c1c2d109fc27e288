"""A fit's seconds at the reference machine, estimated from the capture bench's reference fit of the same
capture (`reports/captures/bench.json`, alone on the reference machine) and the run's schedule:

    t(start) (S' / S) + s (N' - S') + post

S, S': the last stage's first step in the reference fit and the run; N': the run's steps; t(start): the
reference fit's seconds when its last stage began, interpolated over its held-out evaluations (every
``eval_every`` steps, the last at its final step), scaled with the steps before the last stage; s: its last
stage's seconds a step between the first and the last evaluation inside it; post: its seconds after the
last step (colour trials, held-out evaluation, writing). Also prints the run's stored vertices a surface
cell at its final grid (``bricks`` over the plan's ``surface_cells`` (R / surface_resolution)^2).

    python reports/experiments/2026-12-06/reference_seconds.py CAPTURE metrics.json [metrics.json ...]
"""
import json
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
EVAL_EVERY = 250  # FitConfig.eval_every's default, the bench's

fit = json.load(open(os.path.join(ROOT, "reports", "captures", "bench.json")))["fits"][f"{sys.argv[1]}: default"]
ref = fit["metrics"]
steps, start = ref["schedule"]["steps_full"], ref["schedule"]["stages"][-1][0]
times = [t for t, _ in fit["curve"]]
at = [steps] + [EVAL_EVERY * k for k in range(steps // EVAL_EVERY, 0, -1)][: len(times) - 1]  # from the end
at, times = np.array(at[::-1], float), np.array(times[-len(at):])
t_start = float(np.interp(start, at, times))
s = (times[-1] - t_start) / (steps - start)  # the whole stage, its first steps (compiling, occupancy) included
post = ref["seconds"]["fit"] - times[-1]
print(f"reference {sys.argv[1]}: {steps} steps, {ref['seconds']['fit']:.0f} s; last stage from {start} at "
      f"{s:.4f} s a step; {t_start:.0f} s before it, {post:.0f} s after the last step")
for path in sys.argv[2:]:
    m = json.load(open(path))
    n, s2 = m["schedule"]["steps_full"], m["schedule"]["stages"][-1][0]
    plan, r = m["schedule"]["plan"], m["schedule"]["stages"][-1][1]
    cells = plan["surface_cells"] * (r / plan["surface_resolution"]) ** 2
    vertices = m["bricks"]["full"]["vertices"]
    print(f"{path}: {n} steps, last stage from {s2}: about {t_start * s2 / start + s * (n - s2) + post:.0f} s; "
          f"{vertices / cells:.1f} stored vertices a surface cell at {r}^3")
