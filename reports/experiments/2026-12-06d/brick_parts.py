"""A fit's training steps at two brick sizes on a capture, side by side: measured seconds against the plan's count.

    python reports/experiments/2026-12-06d/brick_parts.py DATASET SCRATCH [--rounds 2] [--steps 120] [--last8 464]
        [--last4 464]

Runs the default fit with ``brick`` 8 and 4 in turn (``--rounds`` times, alternating, alone on the machine),
each on an explicit schedule (64 -> 144 -> 288 -> the last grid: ``--last8`` / ``--last4`` vertices at each
size, 464 by default, the statue's default stages), and stops it ``--steps`` steps into the last stage.
For those steps (the first 20 skipped, the TV's steps and the others alike) it prints the median seconds a
step, the samples and stored floats the step counts, and measured / counted
(:func:`mi_voldis.fit.schedule.counted_step_seconds` at the reference rates): where the ratio is the same at
both sizes the plan's count prices a brick size right; the rest of the ratio is the machine's speed against
the reference.
"""
import argparse
import json
import shutil
import statistics
import sys
import time
from pathlib import Path

import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
sys.path.insert(0, ".")
from mi_voldis.fit import problem as problem_module  # noqa: E402
from mi_voldis.fit.config import FitConfig  # noqa: E402
from mi_voldis.fit.run import run_fit  # noqa: E402
from mi_voldis.fit.schedule import BACKENDS  # noqa: E402

parser = argparse.ArgumentParser()
parser.add_argument("dataset")
parser.add_argument("scratch", help="a new folder for the runs (removed at the end)")
parser.add_argument("--rounds", type=int, default=2)
parser.add_argument("--steps", type=int, default=120)
parser.add_argument("--last8", type=int, default=464)
parser.add_argument("--last4", type=int, default=464)
args = parser.parse_args()
scratch = Path(args.scratch)
scratch.mkdir()  # refuses an existing folder: nothing of the user's is touched
LAST, SKIP = 450, 20
LAST_GRID = {8: args.last8, 4: args.last4}
rates = BACKENDS["llvm"]


class Done(Exception):
    pass


rows, last = [], {}
FieldFit = problem_module.FieldFit
before, loss = FieldFit.before_step, FieldFit.loss


def before_step(self, step):
    dr.sync_thread()
    now = time.perf_counter()
    if last.get("step", -1) >= LAST + SKIP:
        rows.append({**last["stats"], "seconds": now - last["t"], "step": last["step"]})
    if step >= LAST + SKIP + args.steps:
        raise Done
    out = before(self, step)
    dr.sync_thread()
    last.update(step=step, t=time.perf_counter())
    return out


def counting_loss(self, step):
    value, stats = loss(self, step)
    last["stats"] = {"samples": stats["samples"], "floats": stats["floats"]}
    return value, stats


FieldFit.before_step, FieldFit.loss = before_step, counting_loss
result = {}
for r in range(args.rounds):
    for brick in (8, 4):
        rows.clear()
        schedule = [[0, 64], [150, 144], [300, 288], [LAST, LAST_GRID[brick]]]
        last.clear()
        cfg = FitConfig.from_sources(None, [f"brick={brick}", f"resolution_schedule={json.dumps(schedule)}",
                                            f"steps_full={LAST + SKIP + args.steps + 10}"])
        try:
            run_fit(args.dataset, str(scratch / f"b{brick}_{r}"), cfg, progress=False)
        except Done:
            pass
        sec = statistics.median(x["seconds"] for x in rows)
        samples = statistics.median(x["samples"] for x in rows)
        floats = statistics.median(x["floats"] for x in rows)
        counted = (samples * rates.sample_ns + floats * rates.float_ns) * 1e-9
        result.setdefault(brick, []).append(sec / counted)
        print(f"round {r} brick {brick} at {LAST_GRID[brick]}^3: {sec * 1e3:.1f} ms a step, "
              f"{samples / 1e3:.0f} k samples, "
              f"{floats / 1e6:.2f} M floats, counted {counted * 1e3:.1f} ms at the reference: measured / counted "
              f"{sec / counted:.3f}", flush=True)
        dr.flush_malloc_cache()
for brick, ratios in result.items():
    rounds = ", ".join(f"{x:.3f}" for x in ratios)
    print(f"brick {brick}: measured / counted {statistics.median(ratios):.3f} (rounds {rounds})")
print(f"brick 4 over brick 8: {statistics.median(result[4]) / statistics.median(result[8]):.3f}")
shutil.rmtree(scratch)
