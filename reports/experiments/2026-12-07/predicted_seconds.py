"""Each refit's seconds alone on the machine, predicted from the capture bench's fit of the same capture
(bench_runs/, timed alone): the refits keep the bench fits' grids and stages (the rates only set the last
stage's length), so a refit's full phase is the bench fit's less its last stage's steps at their mean seconds,
plus the refit's last-stage steps at that mean; the fit adds what followed the bench's full phase (the statue's
background refit).

    python reports/experiments/2026-12-07/predicted_seconds.py
"""
import gzip
import json
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
for capture in ("fern", "horns", "statue", "garden"):
    bench = json.load(open(os.path.join(HERE, "bench_runs", capture, "metrics.json")))
    refit = json.load(open(os.path.join(HERE, f"{capture}_rates_metrics.json")))
    if refit["schedule"]["stages"] != bench["schedule"]["stages"] or refit["grid"] != bench["grid"]:
        raise SystemExit(f"{capture}: the refit's stages or grid differ from the bench fit's: no prediction")
    log = json.load(gzip.open(os.path.join(HERE, "bench_runs", capture, "log.json.gz")))
    start = bench["schedule"]["stages"][-1][0]
    mean = float(np.mean([e["step_seconds"] for e in log if "samples" in e and e["step"] > start + 2
                          and e.get("phase", "full").startswith("full")]))
    n_bench, n_refit = bench["schedule"]["steps_full"] - start, refit["schedule"]["steps_full"] - start
    besides = bench["seconds"]["phase_full"] - n_bench * mean
    after = bench["seconds"]["fit"] - bench["seconds"]["phase_full"]
    plan = refit["schedule"]["plan"]
    print(f"{capture}: last stage {n_bench} -> {n_refit} steps at {mean * 1e3:.1f} ms; full phase "
          f"{bench['seconds']['phase_full']:.0f} -> about {besides + n_refit * mean:.0f} s (its budget "
          f"{plan['budget_seconds']:.0f}); fit {bench['seconds']['fit']:.0f} -> about "
          f"{besides + n_refit * mean + after:.0f} s (of {60 * plan['minutes']:.0f})")
