"""Manipulation tasks on a fitted run: removal, transform, camouflage, nonneg, semantic.

Each reads RUN/ (from scripts/train.py) and writes RUN/<task>/: the edited volumes (.vol), scene.xml
(renders the edit through ``mi.load_file`` after ``import mi_voldis``), layered EXRs and PNG previews
of the held-out views, config.json (its settings), metrics.json and, for optimised tasks, loss.png.
Optimised tasks all run through :func:`mi_voldis.optim.loop.optimize` (checkpoints, ``resume``).
"""
import json
import os

from ..io.run_folder import check_output, content_stamp, dataset_inputs, run_files, staged
from . import camouflage, nonneg, removal, semantic, transform
from .base import FittedRun, TaskOutput
from .settings import SETTINGS

TASKS = {"removal": removal.run, "transform": transform.run, "camouflage": camouflage.run,
         "nonneg": nonneg.run, "semantic": semantic.run}
MAY_CHANGE = ("checkpoint_every",)  # the task setting a resumed task may change: it shapes no result


def task_settings(task, settings=None):
    """The typed settings of ``task``: ``settings`` as given, or a dict of values over the defaults."""
    if task not in TASKS:
        raise ValueError(f"unknown task '{task}' (expected one of {', '.join(TASKS)})")
    cls = SETTINGS[task]
    if isinstance(settings, cls):
        settings.check()
        return settings
    return cls.from_sources(**dict(settings or {}))


def run_task(run_dir, task, settings=None, dataset=None, progress=True, out=None, keep_checkpoints=False,
             restart=False):
    """Run ``task`` with ``settings`` (its settings class, or a dict of values) on the fitted run in
    ``run_dir``; returns the output folder (``out``, default RUN/<task>). Its scene refers to the run's
    unchanged fields in place; its checkpoints are removed when it finishes unless ``keep_checkpoints``.
    ``out`` may not be, hold or lie inside the run's files or its dataset; ``settings.resume``
    continues ``OUT.partial`` of the same task, settings and run only; ``restart`` discards it."""
    settings = task_settings(task, settings)  # checked before anything is read or written
    final = out or os.path.join(run_dir, task)
    named = dataset or _recorded_dataset(run_dir)
    check_output(final, run_files(run_dir) + (dataset_inputs(named) if named else []), settings.resume, restart,
                 program="optimize")
    run = FittedRun(run_dir, dataset)
    inputs = run_files(run_dir) + dataset_inputs(run.dataset.root)
    job = {"task": task, "settings": {k: v for k, v in settings.to_dict().items() if k != "resume"},
           "dataset": os.path.abspath(run.dataset.root),
           "run_files": {os.path.relpath(path, run_dir): content_stamp(path) for path, _ in run_files(run_dir)}}
    with staged(final, settings.resume, keep_checkpoints, inputs, restart, "optimize", job, MAY_CHANGE) as stage:
        TASKS[task](run, TaskOutput(run, task, settings, stage, final), progress)
    return final


def _recorded_dataset(run_dir):
    """The dataset folder a run's config.json names, or None (FittedRun then says what is wrong)."""
    try:
        with open(os.path.join(run_dir, "config.json")) as f:
            record = json.load(f).get("dataset")
    except (OSError, ValueError, AttributeError):
        return None
    path = record.get("path") if isinstance(record, dict) else record
    return path if isinstance(path, str) else None
