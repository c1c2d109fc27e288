"""The optimisation driver: one loop for fitting phases and manipulation tasks.

A *problem* says what is optimised and how (duck-typed):

* ``params``: a ``mi.SceneParameters`` (or dict) holding the tensors or flat arrays; ``keys``: those to optimise;
* ``loss(step)`` -> ``(loss, stats)``: a differentiable Dr.Jit scalar built from renders, and a dict of
  Python numbers for the log (e.g. PSNR, samples evaluated);
* optional ``before_step(step)`` (schedules: resolution changes, occupancy updates),
  ``extra_gradients(step, grads)`` (regularisers with analytic gradients, update masks) and
  ``after_step(step)``.

The loop does the rest: backward pass, Adam with exponential learning-rate decay, progress bar,
a log of loss / PSNR / time / samples per second, and checkpoints it can resume from.
"""
import time

import drjit as dr
import numpy as np

from ..progress import Progress


def _flat(array):
    """The flat array of a tensor (flat arrays as they are)."""
    return array.array if dr.is_tensor_v(array) else array


def decay(step, steps, final_ratio):
    """Learning-rate factor: exponential from 1 at step 0 to ``final_ratio`` at the last step."""
    return final_ratio ** (step / max(steps - 1, 1))


def optimize(problem, adam, *, steps, start=0, final_ratio=0.1, log=None, desc="optimise", checkpoint=None,
             checkpoint_every=0, checkpoint_seconds=None, eval_fn=None, eval_every=0, progress=True):
    """Run ``problem`` from ``start`` to ``steps`` (a number, or a function giving it, read again every
    step: a schedule may stretch or shrink while it runs). ``checkpoint(step)`` is called every
    ``checkpoint_every`` steps, or with ``checkpoint_seconds`` after the first step that ends that many
    seconds (wall clock) after the last checkpoint or the start, and at the end; ``eval_fn(step)`` -> dict
    every ``eval_every`` steps (merged into the log). Returns the log (a list of dicts, one per logged
    step)."""
    log = [] if log is None else log
    elapsed = log[-1]["time"] if log else 0.0
    end = steps if callable(steps) else (lambda: steps)
    bar = Progress(end() - start, desc, progress)  # a bar on a terminal, lines in a log
    step = start - 1
    saved = time.perf_counter()
    while step + 1 < end():
        step += 1
        bar.total = end() - start
        t0 = time.perf_counter()
        if hasattr(problem, "before_step"):
            problem.before_step(step)
        params = problem.params
        for key in problem.keys:
            dr.enable_grad(params[key])
        params.update()
        loss, stats = problem.loss(step)
        dr.backward(loss)
        grads = {key: _flat(dr.grad(params[key])) for key in problem.keys}
        if hasattr(problem, "extra_gradients"):
            grads = problem.extra_gradients(step, grads)
        adam.step(params, grads, decay(step, end(), final_ratio))
        params.update()
        if hasattr(problem, "after_step"):
            problem.after_step(step)
        loss_value = float(np.array(loss).ravel()[0])
        dr.sync_thread()
        dt = time.perf_counter() - t0
        elapsed += dt
        row = {"step": step + 1, "time": elapsed, "loss": loss_value, "step_seconds": dt, "phase": desc, **stats}
        if "samples" in stats:
            row["msps"] = stats["samples"] / dt / 1e6
        if eval_fn is not None and eval_every and ((step + 1) % eval_every == 0 or step + 1 == end()):
            row.update(eval_fn(step + 1))
        log.append(row)
        bar.update(1)
        bar.set_postfix({k: f"{row[k]:.4g}" for k in ("loss", "psnr", "msps") if k in row})
        due = (checkpoint_every and (step + 1) % checkpoint_every == 0) or step + 1 == end() or (
            checkpoint_seconds is not None and time.perf_counter() - saved >= checkpoint_seconds)
        if checkpoint is not None and (checkpoint_every or checkpoint_seconds is not None) and due:
            checkpoint(step + 1)
            saved = time.perf_counter()
    bar.close()
    return log

