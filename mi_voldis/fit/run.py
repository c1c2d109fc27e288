"""A fitting run: stage, fit, write, then swap the run folder into place (:mod:`mi_voldis.io.run_folder`).

RUN/ holds the fields (``<role>_grid.npz``), ``scene.xml`` (renders them through ``mi.load_file``),
``config.json`` (the settings and the dataset they were fitted on), ``metrics.json``, ``log.json``,
``training.png`` and ``previews/`` (and while it runs ``checkpoints/``). ``resume`` continues from
RUN.partial/checkpoints/last.npz after a crash or kill -9, for the same dataset (its files' names,
sizes and contents) and settings (:data:`MAY_CHANGE` aside) only.
"""
import json
import os
import sys
import time

import numpy as np

from ..data import load_dataset
from ..data.scene_box import fitting_box
from ..io.run_folder import check_output, dataset_inputs, fingerprint, peak_rss_mib, staged, write_json
from ..plots import plot_log
from ..scene import write_scene
from .config import FitConfig
from .fields import sample_step, scene_integrator
from .report import evaluate, write_previews
from .schedule import backend
from .train import fit

PREVIEW = "previews"
CHECKPOINT = os.path.join("checkpoints", "last.npz")
# settings a resumed fit may change: they shape no result
MAY_CHANGE = ("checkpoint_every", "checkpoint_minutes", "eval_every")


def finished(out, dataset, sets, ignore=()):
    """``out`` holds a finished fit of ``dataset`` with exactly the settings ``sets`` (``--set`` strings)
    give, but those named in ``ignore``: what a caller may reuse instead of fitting again."""
    try:
        with open(os.path.join(out, "config.json")) as f:
            config = json.load(f)
    except (OSError, ValueError):
        return False
    record = config.get("dataset", {})
    config = FitConfig.recorded(config)  # what was fitted, on what, aside; settings added since at their old values
    same_data = os.path.realpath(record.get("path", "")) == os.path.realpath(dataset)
    expected = FitConfig.from_sources(None, sets).for_backend(backend()).to_dict()  # 'auto' as a run records it
    for key in ignore:
        config.pop(key, None), expected.pop(key, None)
    return os.path.isfile(os.path.join(out, "metrics.json")) and same_data and config == expected


def run_fit(dataset_path, out, cfg=None, resume=False, progress=True, fmt="auto", holdout=8, keep_checkpoints=False,
            factor=None, restart=False):
    """Fit the dataset at ``dataset_path`` into the run folder ``out``; returns the metrics.
    ``keep_checkpoints``: the finished run keeps ``checkpoints/last.npz`` (its final state, from which
    :mod:`mi_voldis.bench.strategies` refits the background another way). ``resume`` continues
    ``OUT.partial`` (refused for another dataset or other settings); ``restart`` discards it.
    The output and the dataset are checked before anything is removed."""
    cfg = (cfg or FitConfig()).for_backend(backend())  # config.json records the rays and speed planned with
    inputs = dataset_inputs(dataset_path)
    check_output(out, inputs, resume, restart, program="train")
    dataset = load_dataset(dataset_path, fmt, holdout, factor)
    record = dataset_record(dataset_path, dataset, holdout, factor)
    job = {"settings": cfg.to_dict(), "dataset": {k: record[k] for k in ("path", "format", "holdout", "factor")},
           "dataset_files": fingerprint(dataset_path, skip=[out])}
    with staged(out, resume, keep_checkpoints, inputs, restart, "train", job, MAY_CHANGE) as stage:
        for line in dataset.meta.get("notes", []) if progress else ():
            print(f"note: {line}", file=sys.stderr)
        if dataset.effects is not None and progress:
            use = "the background leaves them to its prior" if cfg.bg_strategy == "guided" else \
                f"ignored: only bg_strategy 'guided' reads them, not '{cfg.bg_strategy}'"
            print(f"note: effect masks (the object's shadow) on {int(dataset.effects.any(axis=(1, 2)).sum())} of "
                  f"{len(dataset.images)} views: {use}", file=sys.stderr)
        # 'auto' resolved from the cameras
        space = fitting_box(dataset, cfg.space, cfg.contract_shell, cfg.contract_radius).kind
        write_json(os.path.join(stage, "config.json"), {**cfg.to_dict(), "dataset": record, "space_used": space})
        t0 = time.perf_counter()
        inputs, state = fit(dataset, os.path.join(stage, CHECKPOINT), cfg, resume=resume, progress=progress)
        fit_seconds = time.perf_counter() - t0
        metrics = write_run(stage, inputs, state, fit_seconds)
    return metrics


def dataset_record(path, dataset, holdout, factor):
    """What ``config.json`` records of the dataset: enough to load it again as the fit saw it."""
    return {"path": os.path.abspath(path), "format": dataset.meta["format"], "holdout": holdout, "factor": factor,
            "color_space": dataset.meta.get("color_space", "sRGB"), "notes": dataset.meta.get("notes", [])}


def write_run(stage, inputs, state, fit_seconds):
    """Everything a finished fit writes beside its checkpoint; returns the metrics."""
    ds, cfg = inputs.ds, inputs.cfg
    integrator, props = scene_integrator(inputs, state)
    summary, rows, renders = evaluate(ds, integrator)
    write_scene(stage, {role: state.fields[role] for role in ("full", "bg")}, props,
                [ds.cameras[v] for v in ds.test])
    write_previews(os.path.join(stage, PREVIEW), renders, list(ds.test[: cfg.preview_views]),
                   ds.meta.get("background_color"))
    plot_log(os.path.join(stage, "training.png"), state.log, f"{ds.name}: loss and PSNR against time")
    train_rows = [r for r in state.log if "samples" in r]
    metrics = {
        "dataset": ds.name, "views": {"train": len(ds.train), "test": len(ds.test)},
        "held_out": summary, "per_view": rows,
        "seconds": {"fit": fit_seconds, **{f"phase_{k}": v for k, v in state.phase_times.items()}},
        "peak_rss_mib": peak_rss_mib(),
        "msps_mean": float(np.mean([r["msps"] for r in train_rows])) if train_rows else None,
        # the fitted scene's held-out renders (its rules: fitted_scene_properties), and the last training steps'
        "evaluated_samples_per_ray": summary.get("samples_per_ray"),
        "train_samples_per_ray": float(np.mean([r["samples"] for r in train_rows[-50:]]) / cfg.batch_rays)
        if train_rows else None,
        "max_samples_per_ray": cfg.max_samples, "step_size": sample_step(cfg, state),
        "grid": {r: list(s.shape) for r, s in state.fields.items()},
        "bricks": {r: {"allocated": s.layout.allocated, "of": int(s.layout.table.size),
                       "vertices": s.layout.allocated * s.layout.vertices_per_brick} for r, s in state.fields.items()},
        "schedule": {"plan": state.plan, "steps_full": state.steps_full, "stages": state.schedule},
        "space": inputs.space.kind,
        "sh_degree": state.fields["full"].sh_degree, "sh_color": "grey" if state.fields["full"].grey else "rgb",
        "sh_choice": state.sh_choice,
        "box": {"kind": inputs.box.kind, "lo": state.lo.tolist(), "hi": state.hi.tolist()},
        "occupied_fraction": integrator.occupancy.fraction if integrator.occupancy is not None else None,
        "empty_bg_color_fraction": state.empty_color_fraction,
        "bg_strategy": cfg.bg_strategy, "bg_prior": state.prior,
    }
    write_json(os.path.join(stage, "metrics.json"), metrics)
    write_json(os.path.join(stage, "log.json"), state.log)
    return metrics
