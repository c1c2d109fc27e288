"""#42: what the second stage of a fit gains on its held-out evaluation views (test_psnr in log.json), from the
last evaluation at or before the stage starts to the first one 200 or more steps into it, beside the colour
trial's gain of the same run (metrics.json sh_choice).

    python reports/experiments/2026-11-28/stage_gain/gain.py RUN...
"""
import json
import os
import sys


def gain(run):
    with open(os.path.join(run, "log.json")) as f:
        log = json.load(f)
    with open(os.path.join(run, "metrics.json")) as f:
        met = json.load(f)
    stages = met["schedule"]["stages"]
    points = [(e["step"], e["test_psnr"]) for e in log if "test_psnr" in e]
    start = stages[1][0]
    before = [p for s, p in points if s <= start]
    after = [(s, p) for s, p in points if s >= start + 200]
    choice = met.get("sh_choice") or {}
    trial = choice.get("val_psnr_degree1", 0.0) - choice.get("val_psnr_degree0", 0.0)
    return met.get("sh_degree"), stages, before[-1], after[0], met["held_out"]["psnr"], trial


for run in sys.argv[1:]:
    try:
        degree, stages, b, (step, a), final, trial = gain(run)
    except (OSError, KeyError, IndexError, TypeError) as e:
        print(run, "not read:", e)
        continue
    print(f"{run:40s} deg{degree} stages {[s[1] for s in stages]} at {stages[1][0]}: {b:.2f} -> {step}:{a:.2f} "
          f"gain {a - b:.2f} final {final:.2f} trial {trial:+.2f}")
