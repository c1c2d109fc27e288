"""Where the counted last stage (mi_voldis.fit.train.recount, at every replan) would have ended a finished
default fit, replayed over its logged counts: the fit's steps do not depend on the end, so this is what
the rule computes from the same counts (the learning rate's decay, which follows the end, aside).

    python reports/experiments/2026-12-05c/replay_recount.py RUN [RUN ...]
"""
import json
import os
import sys
from types import SimpleNamespace

import mi_voldis  # noqa: F401  (points Dr.Jit at a working libLLVM)
from mi_voldis.fit.schedule import REPLAN_EVERY
from mi_voldis.fit.train import recount

for run in sys.argv[1:]:
    schedule = json.load(open(os.path.join(run, "metrics.json")))["schedule"]
    log = [r for r in json.load(open(os.path.join(run, "log.json"))) if r.get("phase", "").startswith("full")]
    plan = {k: v for k, v in schedule["plan"].items() if k not in ("recounted", "rescaled")}
    stages = schedule["stages"]
    steps_at_start = [end for step, end in schedule["plan"]["rescaled"] if step <= stages[-1][0]]
    state = SimpleNamespace(plan=plan, schedule=stages, log=log,
                            steps_full=steps_at_start[-1] if steps_at_start else schedule["steps_full"])
    ends = []
    for step in range(stages[-1][0] + REPLAN_EVERY, log[-1]["step"], REPLAN_EVERY):
        if step >= state.steps_full:
            break
        state.log = [r for r in log if r["step"] <= step]
        recount(state, step)
        ends.append((step, state.steps_full, round(plan["recounted"]["step_seconds"], 4)))
    print(f"{run}: ran {schedule['steps_full']} steps; recounted at every replan: {ends[0]} ... {ends[-1]} "
          f"(step, end, seconds a step)")
