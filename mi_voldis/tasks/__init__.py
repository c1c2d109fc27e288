"""Manipulation tasks on a fitted run: removal, transform, camouflage, nonneg, semantic.

Each reads RUN/ (from scripts/train.py) and writes RUN/<task>/: the edited volumes (.vol), scene.xml
(renders the edit through ``mi.load_file`` after ``import mi_voldis``), layered EXRs and PNG previews
of the held-out views, config.json (its settings), metrics.json and, for optimised tasks, loss.png.
Optimised tasks all run through :func:`mi_voldis.optim.loop.optimize` (checkpoints, ``resume``).
"""
import os

from ..io.run_folder import staged
from . import camouflage, nonneg, removal, semantic, transform
from .base import FittedRun, TaskOutput
from .settings import SETTINGS

TASKS = {"removal": removal.run, "transform": transform.run, "camouflage": camouflage.run,
         "nonneg": nonneg.run, "semantic": semantic.run}


def task_settings(task, settings=None):
    """The typed settings of ``task``: ``settings`` as given, or a dict of values over the defaults."""
    if task not in TASKS:
        raise ValueError(f"unknown task '{task}' (expected one of {', '.join(TASKS)})")
    cls = SETTINGS[task]
    if isinstance(settings, cls):
        settings.check()
        return settings
    return cls.from_sources(**dict(settings or {}))


def run_task(run_dir, task, settings=None, dataset=None, progress=True, out=None, keep_checkpoints=False):
    """Run ``task`` with ``settings`` (its settings class, or a dict of values) on the fitted run in
    ``run_dir``; returns the output folder (``out``, default RUN/<task>). Its scene refers to the run's
    unchanged fields in place; its checkpoints are removed when it finishes unless ``keep_checkpoints``."""
    settings = task_settings(task, settings)  # checked before anything is read or written
    run = FittedRun(run_dir, dataset)
    final = out or os.path.join(run.dir, task)
    with staged(final, settings.resume, keep_checkpoints) as stage:
        TASKS[task](run, TaskOutput(run, task, settings, stage, final), progress)
    return final
