"""A fitting run from the command line: stage, fit, write, then swap the run directory into place.

Everything is written into RUN.partial/ (checkpoints included) and RUN.partial is renamed to RUN
only when complete, so RUN is never half-overwritten; ``resume`` continues from
RUN.partial/checkpoints/last.npz after a crash or kill -9.
"""
import os
import shutil
import time

import numpy as np

from ..data import load_dataset
from . import report
from .config import FitConfig
from .train import fit

PREVIEW = "previews"


def staging(out):
    return out.rstrip("/") + ".partial"


def run_fit(dataset_path, out, cfg=None, resume=False, progress=True, fmt="auto", holdout=8):
    cfg = cfg or FitConfig()
    stage = staging(out)
    if resume and not os.path.isdir(stage):
        raise ValueError(f"{stage}: nothing to resume (no staged run)")
    if not resume:
        shutil.rmtree(stage, ignore_errors=True)
    os.makedirs(stage, exist_ok=True)
    dataset = load_dataset(dataset_path, fmt, holdout)
    report.write_json(os.path.join(stage, "config.json"), {**cfg.to_dict(), "dataset": os.path.abspath(dataset_path)})
    t0 = time.perf_counter()
    ctx = fit(dataset, stage, cfg, resume=resume, progress=progress)
    fit_seconds = time.perf_counter() - t0

    bodies = report.write_fields(ctx, stage)
    integrator = ctx.build_integrator()
    if cfg.occupancy_resolution:
        integrator.update_occupancy(cfg.occupancy_resolution, ctx.occupancy_sigma())
    summary, rows, renders = report.evaluate(ctx, integrator)
    report.write_run_scene(ctx, stage, bodies, list(dataset.test))
    report.write_previews(os.path.join(stage, PREVIEW), renders, list(dataset.test[: cfg.preview_views]))
    report.plot_log(os.path.join(stage, "training.png"), ctx.log, f"{dataset.name}: loss and PSNR against time")
    train_rows = [r for r in ctx.log if "samples" in r]
    metrics = {
        "dataset": dataset.name, "views": {"train": len(dataset.train), "test": len(dataset.test)},
        "held_out": summary, "per_view": rows,
        "seconds": {"fit": fit_seconds, **{f"phase_{k}": v for k, v in ctx.phase_times.items()}},
        "peak_rss_mib": report.peak_rss_mib(),
        "msps_mean": float(np.mean([r["msps"] for r in train_rows])) if train_rows else None,
        "evaluated_samples_per_ray": float(np.mean([r["samples"] for r in train_rows[-50:]]) / cfg.batch_rays)
        if train_rows else None,
        "max_samples_per_ray": cfg.max_samples, "step_size": ctx.step_size(),
        "grid": {r: list(s.shape) for r, s in ctx.states.items()},
        "sh_degree": ctx.states["full"].sh_degree, "sh_choice": ctx.sh_choice,
        "box": {"kind": dataset.box.kind, "lo": ctx.lo.tolist(), "hi": ctx.hi.tolist()},
        "occupied_fraction": integrator.occupancy.fraction if integrator.occupancy is not None else None,
        "empty_bg_color_fraction": getattr(ctx, "empty_color_fraction", None),
        "bg_strategy": cfg.bg_strategy,
    }
    report.write_json(os.path.join(stage, "metrics.json"), metrics)
    report.write_json(os.path.join(stage, "log.json"), ctx.log)
    commit(stage, out)
    return metrics


def commit(stage, out):
    """Replace ``out`` by the finished ``stage`` with renames only."""
    old = out.rstrip("/") + ".old"
    shutil.rmtree(old, ignore_errors=True)
    if os.path.exists(out):
        os.replace(out, old)
    os.replace(stage, out)
    shutil.rmtree(old, ignore_errors=True)
