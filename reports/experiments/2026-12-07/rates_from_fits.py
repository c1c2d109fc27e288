"""The llvm rates from whole fits timed alone (the capture bench's default fits): what a last-stage step costs
with everything the full phase spends around its steps, so that a counted plan ends within its budget.

Per fit: the full phase's wall seconds W; the seconds its plan gave the stages before the last, P (the plan's
coarse-stage model, as `recount` charges them), and the steps of the last stage, N, with their mean samples S
and stored floats F a step (every step after the stage's first two). The effective step

    t = (W - P) / N

holds the last stage's own steps (the TV's every ``tv_every``-th, the occupancy updates every
``occupancy_every``) and what the phase spends beside its steps (the held-out evaluations every ``eval_every``
steps, the checkpoints, the earlier stages' departure from their model), shared over the last stage's steps.
Then x (seconds a sample) and y (a float) solving  t = x S + y F  in least squares of the relative error, and
the same rates scaled to cover the dearest fit (none counted below what it took). Also prints the mean step of
the last stage alone and each fit counted at the plan's rates.

    python reports/experiments/2026-12-07/rates_from_fits.py RUN [RUN ...]

RUN: a folder with the fit's metrics.json and its log.json gzipped (log.json.gz), as in bench_runs/.
"""
import gzip
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.getcwd())
from mi_voldis.fit.schedule import cost_ahead, plan_cost  # noqa: E402

rows = []
for run in sys.argv[1:]:
    m = json.load(open(os.path.join(run, "metrics.json")))
    plan, schedule, n_full = m["schedule"]["plan"], m["schedule"]["stages"], m["schedule"]["steps_full"]
    start = schedule[-1][0]
    cost = plan_cost(plan, schedule[0][1])
    before = cost_ahead(schedule, n_full, 0, cost) - cost_ahead(schedule, n_full, start, cost)
    log = [e for e in json.load(gzip.open(os.path.join(run, "log.json.gz")))
           if "samples" in e and "step_seconds" in e and e["step"] > start + 2
           and e.get("phase", "full").startswith("full")]
    mean, s, f = (np.mean([e[k] for e in log]) for k in ("step_seconds", "samples", "floats"))
    wall = m["seconds"]["phase_full"]
    t = (wall - before) / (n_full - start)
    counted = (s * plan["sample_ns"] + f * plan["float_ns"]) * 1e-9
    rows.append(dict(name=os.path.basename(run.rstrip("/")), t=t, mean=mean, s=s, f=f, counted=counted, wall=wall,
                     budget=plan["budget_seconds"], before=before, n=n_full - start, fit=m["seconds"]["fit"],
                     minutes=plan["minutes"]))

a = np.array([[r["s"], r["f"]] for r in rows])
t = np.array([r["t"] for r in rows])
x, y = np.linalg.lstsq(a / t[:, None], np.ones(len(t)), rcond=None)[0]  # relative residuals
cover = float(np.max(t / (a @ [x, y])))
print(f"least squares: {x * 1e9:.1f} ns a sample, {y * 1e9:.3f} ns a float; covering every fit (x{cover:.3f}): "
      f"{x * cover * 1e9:.1f} ns, {y * cover * 1e9:.3f} ns")
for r, pred in zip(rows, a @ [x, y]):
    print(f"{r['name']}: fit {r['fit']:.0f} s ({r['minutes']:.2f} min); full phase {r['wall']:.0f} s against its "
          f"budget {r['budget']:.0f} ({r['wall'] / r['budget']:.3f}x); stages before the last planned "
          f"{r['before']:.0f} s; last stage {r['n']} steps ({r['s'] / 1e3:.0f} k samples, {r['f'] / 1e6:.2f} M floats) "
          f"at {r['mean'] * 1e3:.1f} ms a step, effective {r['t'] * 1e3:.1f} ms; counted at the plan's rates "
          f"{r['counted'] * 1e3:.1f} ms "
          f"({r['t'] / r['counted']:.3f}x), at least squares' {pred * 1e3:.1f} ({r['t'] / pred:.3f}x)")
