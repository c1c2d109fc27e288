"""A fit's last-stage steps by kind, from its log: plain steps, the TV's (every ``tv_every`` = 4th, the log's
step = 1 mod 4) and the occupancy updates (every 100th, step = 1 mod 100), each kind's mean against the plain
steps', with the TV's extra per stored float.

    python reports/experiments/2026-12-07/step_parts.py RUN [RUN ...]   (RUN: metrics.json and log.json.gz)
"""
import gzip
import json
import os
import sys

import numpy as np

for run in sys.argv[1:]:
    m = json.load(open(os.path.join(run, "metrics.json")))
    start, resolution = m["schedule"]["stages"][-1]
    log = [e for e in json.load(gzip.open(os.path.join(run, "log.json.gz")))
           if "samples" in e and "step_seconds" in e and e["step"] > start + 2
           and e.get("phase", "full").startswith("full")]
    step = np.array([e["step"] for e in log])
    t, s, f = (np.array([e[k] for e in log]) for k in ("step_seconds", "samples", "floats"))
    occupancy = step % 100 == 1
    tv = (step % 4 == 1) & ~occupancy
    plain = ~occupancy & ~tv
    base = t[plain].mean()
    name = os.path.basename(run.rstrip("/"))
    print(f"{name}: {resolution}^3, plain steps {base * 1e3:.1f} ms ({s.mean() / 1e3:.0f} k "
          f"samples, {f.mean() / 1e6:.2f} M floats), TV steps +{(t[tv].mean() - base) * 1e3:.1f} ms "
          f"({(t[tv].mean() - base) / f.mean() * 1e9:.2f} ns a float), occupancy updates "
          f"+{(t[occupancy].mean() - base) * 1e3:.0f} ms; mean {t.mean() * 1e3:.1f} ms")
