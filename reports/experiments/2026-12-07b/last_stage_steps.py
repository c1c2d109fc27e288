"""Seconds a step of a fit's last stage took, mean and median, from its log (``log.json`` or ``log.json.gz``).

    python reports/experiments/2026-12-07b/last_stage_steps.py RUN [RUN ...]
"""
import gzip
import json
import os
import sys

import numpy as np

for run in sys.argv[1:]:
    m = json.load(open(os.path.join(run, "metrics.json")))
    path = os.path.join(run, "log.json")
    log = json.load(open(path)) if os.path.exists(path) else json.load(gzip.open(path + ".gz"))
    start = m["schedule"]["stages"][-1][0]
    t = np.array([r["step_seconds"] for r in log if "step_seconds" in r and "samples" in r and r["step"] > start + 2])
    print(f"{os.path.basename(run.rstrip('/'))}: {len(t)} last-stage steps, mean {t.mean() * 1e3:.1f} ms, "
          f"median {np.median(t) * 1e3:.1f} ms")
