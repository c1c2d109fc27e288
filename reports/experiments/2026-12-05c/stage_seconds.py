"""Per stage of a default fit's full phase: the median seconds a step took here, its samples and stored
floats, the seconds the plan's reference rates give those counts (`counted_step_seconds`), and the ratio:
how much slower (>1) or faster this machine ran than the reference the plan is costed at. The ratio of the
last stage converts the run's wall clock to the reference machine's.

    python reports/experiments/2026-12-05c/stage_seconds.py RUN [RUN ...]
"""
import json
import os
import sys

import numpy as np


def counted(plan, samples, floats):  # mi_voldis.fit.schedule.counted_step_seconds, without importing Mitsuba
    return plan.get("host_ms", 0.0) / 1e3 + (samples * plan["sample_ns"] + floats * plan["float_ns"]) * 1e-9


for run in sys.argv[1:]:
    metrics = json.load(open(os.path.join(run, "metrics.json")))
    log = [r for r in json.load(open(os.path.join(run, "log.json"))) if r.get("phase", "").startswith("full")
           and "psnr" in r]
    schedule = metrics["schedule"]
    plan, stages, end = schedule["plan"], schedule["stages"], schedule["steps_full"]
    print(f"{run}: {end} steps, fit {metrics['seconds']['fit']:.0f} s, recounted {plan.get('recounted')}")
    ratio = None
    for k, (start, res) in enumerate(stages):
        stop = stages[k + 1][0] if k + 1 < len(stages) else end
        rows = [r for r in log if start < r["step"] <= stop]
        rows = rows[len(rows) // 5:]
        s, t = np.median([r["samples"] for r in rows]), np.median([r["step_seconds"] for r in rows])
        f = np.median([r.get("floats", np.nan) for r in rows])
        c = counted(plan, s, f) if "sample_ns" in plan and np.isfinite(f) else np.nan
        ratio = t / c
        print(f"  {res}^3 from step {start}: {t:.3f} s a step here, {s / 1e6:.2f} M samples, {f / 1e6:.1f} M floats, "
              f"counted {c:.3f} s ({ratio:.2f}x)")
    coarse = [r for r in log if 40 < r["step"] <= 200]
    msps = np.median([r["samples"] / r["step_seconds"] for r in coarse]) / 1e6
    print(f"  the coarse stage here: {msps:.1f} M samples/s (reference {plan['reference_msps']:g}); "
          f"the fit's seconds at the last stage's ratio: {metrics['seconds']['fit'] / ratio:.0f} s")
