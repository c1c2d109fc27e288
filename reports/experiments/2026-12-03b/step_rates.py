"""Median step seconds and M samples a second of a finished run, by range of steps (its log.json).

usage: python step_rates.py RUN [LO:HI ...]   (default ranges: 1:200, the coarse steps the plan calibrates on)
"""
import json
import os
import statistics
import sys

run, ranges = sys.argv[1], sys.argv[2:] or ["1:200"]
log = json.load(open(os.path.join(run, "log.json")))
for r in ranges:
    lo, hi = map(int, r.split(":"))
    rows = [e for e in log if lo <= e["step"] < hi]
    print(f"steps {lo}-{hi - 1}: median step {statistics.median(e['step_seconds'] for e in rows):.4f} s, "
          f"median {statistics.median(e['msps'] for e in rows):.2f} M samples/s ({len(rows)} steps)")
