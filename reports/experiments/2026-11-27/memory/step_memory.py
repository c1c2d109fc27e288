"""What Dr.Jit holds through the parts of a training step: the default training command with Dr.Jit's
allocator figures ("in use / held", from ``dr.whos()``) printed after each part of the steps in STEPS
(the stage start, the loss, the backward pass, the regularisers, Adam, occupancy updates, evaluations).

    python reports/experiments/2026-11-27/memory/step_memory.py -- DATASET --out RUN [train.py flags]

reports/notes.md quotes it on the statue with --set 'resolution_schedule=[[0,64],[200,320]]' --set steps_full=310.
"""
import contextlib
import functools
import io
import os
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4))
sys.path.insert(0, ROOT)

import drjit as dr  # noqa: E402

from mi_voldis.fit import problem, train  # noqa: E402
from mi_voldis.optim import adam  # noqa: E402

STEPS = {199, 200, 201, 202, 251, 252, 253, 300, 301}
current = {"step": -1}


def report(label):
    if current["step"] not in STEPS:
        return
    dr.sync_thread()
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        dr.whos()
    line = [s for s in buf.getvalue().splitlines() if "used" in s][0].split(":", 1)[1].strip()
    print(f"[memory] step {current['step']}, after {label}: {line}", flush=True)


def traced(owner, name, evaluate=False):
    original = getattr(owner, name)

    @functools.wraps(original)
    def wrapper(*args, **kwargs):
        out = original(*args, **kwargs)
        if evaluate:  # the regularisers' lazy sum, as Adam would read it
            dr.eval(out)
        report(name)
        return out
    setattr(owner, name, wrapper)


def main():
    argv = sys.argv[1:]
    rest = argv[argv.index("--") + 1:] if "--" in argv else argv
    before = problem.FieldFit.before_step

    def before_step(self, step):
        current["step"] = step
        report("the step before")
        before(self, step)
        report("before_step (refinement, occupancy)")

    problem.FieldFit.before_step = before_step
    traced(problem.FieldFit, "loss")
    traced(problem.FieldFit, "extra_gradients", evaluate=True)
    traced(problem.FieldFit, "update_occupancy")
    traced(adam.Adam, "step")
    held_out = train.held_out_psnr

    def held_out_traced(inputs, fit):
        evaluate = held_out(inputs, fit)
        if evaluate is None:
            return None

        def wrapper(step):
            out = evaluate(step)
            report("held-out evaluation")
            return out
        return wrapper

    train.held_out_psnr = held_out_traced
    from voldis_cli.train import main as train_main
    train_main(rest)


if __name__ == "__main__":
    main()
