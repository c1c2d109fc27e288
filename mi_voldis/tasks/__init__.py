"""Manipulation tasks on a fitted run: removal, transform, camouflage, nonneg, semantic.

Each reads RUN/ (from scripts/train.py) and writes RUN/<task>/: the edited volumes (.vol), scene.xml
(renders the edit through ``mi.load_file`` after ``import mi_voldis``), layered EXRs and PNG previews
of the held-out views, metrics.json and, for optimised tasks, loss.png. Optimised tasks all run
through :func:`mi_voldis.optim.loop.optimize` (checkpoints, ``resume``).
"""
from . import nonneg, recolor, removal, transform
from .base import FittedRun, TaskOutput

TASKS = {"removal": removal.run, "transform": transform.run, "camouflage": recolor.camouflage,
         "nonneg": nonneg.run, "semantic": recolor.semantic}


def run_task(run_dir, task, options=None, dataset=None):
    """Run ``task`` on the fitted run in ``run_dir``; returns the output folder."""
    if task not in TASKS:
        raise ValueError(f"unknown task '{task}' (expected one of {', '.join(TASKS)})")
    options = dict(options or {})
    for key in ("steps", "checkpoint_every"):  # checked before anything is read or written
        if options.get(key) is not None and int(options[key]) < 1:
            raise ValueError(f"{key} must be at least 1, got {options[key]}")
    run = FittedRun(run_dir, dataset)
    output = TaskOutput(run, task, resume=bool(options.get("resume")))
    return TASKS[task](run, output, options)
