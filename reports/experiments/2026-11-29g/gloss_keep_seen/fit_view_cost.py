"""#42: what a view lattice costs in a fit: per-sample seconds of the full phase's 150 steps after the
progressive-view-dependence onset (half the steps) over the 150 before, both in the final stage. Not a timing
to report alone: processes beside the fit change both windows.

    python reports/experiments/2026-11-29g/gloss_keep_seen/fit_view_cost.py RUN [RUN ...]
"""
import json
import os
import sys

import numpy as np

for run in sys.argv[1:]:
    with open(os.path.join(run, "log.json")) as f:
        log = json.load(f)
    with open(os.path.join(run, "metrics.json")) as f:
        m = json.load(f)
    rows = [r for r in log if r.get("phase", "").startswith("full") and "step_seconds" in r and "test_psnr" not in r]
    onset = int(0.5 * max(r["step"] for r in rows))

    def per_sample(a, b):
        return float(np.median([r["step_seconds"] / r["samples"] for r in rows if a < r["step"] <= b]))

    ratio = per_sample(onset, onset + 150) / per_sample(onset - 150, onset)
    print(f"{run}: stages {m['schedule']['stages']}, onset {onset}, after / before {ratio:.3f}, kernel_scale "
          f"{m['schedule']['plan'].get('kernel_scale')}, held out {m['held_out']['psnr']:.4f} dB")
