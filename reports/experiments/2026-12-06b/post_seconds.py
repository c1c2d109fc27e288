"""The seconds after a fit's last full-phase step (background refit, evaluation, writing) at the reference,
from two runs of the same capture on this machine, one before a change and one after: the capture bench's
reference fit's own seconds after its last step (`reports/captures/bench.json`), times the runs' ratio.
The part after the last step runs NumPy and OpenCV as much as Dr.Jit, so it is scaled by its own ratio,
not by the coarse stage's. Then the after run's whole time at the reference: its full phase as
`../2026-12-06/reference_seconds.py` estimates it, with this post in place of the reference fit's.

    python post_seconds.py CAPTURE BEFORE_RUN AFTER_RUN
"""
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))


def post(run):
    """This machine's seconds from the run's last full-phase step to the end of its fit."""
    metrics = json.load(open(os.path.join(run, "metrics.json")))
    last = max(r["time"] for r in json.load(open(os.path.join(run, "log.json"))) if r.get("phase") == "full")
    return metrics["seconds"]["fit"] - last


capture, before, after = sys.argv[1:4]
ref = json.load(open(os.path.join(ROOT, "reports", "captures", "bench.json")))["fits"][f"{capture}: default"]
ref_post = ref["metrics"]["seconds"]["fit"] - ref["curve"][-1][0]
here = post(before), post(after)
new_post = ref_post * here[1] / here[0]
print(f"{capture}: after the last step, this machine {here[0]:.0f} s before, {here[1]:.0f} s after; "
      f"the reference fit {ref_post:.0f} s, so about {new_post:.0f} s")
script = os.path.join(ROOT, "reports", "experiments", "2026-12-06", "reference_seconds.py")
line = subprocess.run([sys.executable, script, capture, os.path.join(after, "metrics.json")], capture_output=True,
                      text=True, check=True).stdout.splitlines()[-1]
total = float(line.split("about ")[1].split(" s")[0])
print(f"{after}: about {total - ref_post + new_post:.0f} s at the reference ({line.split(': ', 1)[1]})")
