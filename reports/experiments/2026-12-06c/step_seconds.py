"""Where a fit's seconds went on this machine, for runs of one capture compared side by side: the full
phase's steps (their own `step_seconds`, the last stage's mean a step from 50 steps after its start), the
seconds inside the full phase outside its steps (held-out evaluations for the log, checkpoints, stage
changes, occupancy updates), and the seconds after its last step (background phase, evaluation, writing).

    python step_seconds.py RUN [RUN ...]
"""
import json
import os
import sys

import numpy as np

for run in sys.argv[1:]:
    m = json.load(open(os.path.join(run, "metrics.json")))
    log = [r for r in json.load(open(os.path.join(run, "log.json"))) if str(r.get("phase", "")).startswith("full")]
    start = m["schedule"]["stages"][-1][0]
    steps = sum(r["step_seconds"] for r in log)
    last = np.mean([r["step_seconds"] for r in log if r["step"] > start + 50])
    inside = m["seconds"]["phase_full"] - steps
    after = m["seconds"]["fit"] - m["seconds"]["phase_full"]
    print(f"{run}: {len(log)} steps {steps:.1f} s (last stage {last * 1e3:.1f} ms a step), inside the full phase "
          f"outside its steps {inside:.1f} s, after it {after:.1f} s, fit {m['seconds']['fit']:.1f} s; held out "
          f"{m['held_out']['psnr']:.4f} dB")
