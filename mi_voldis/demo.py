"""The whole pipeline on a bundled scene: dataset -> fit -> disentangle -> edits -> EXRs, a labelled
contact sheet and a turntable of the moved object beside the original.

The object is moved by the dataset's own ``moved_transform``, whose ground truth scores every
composition rule (:mod:`mi_voldis.tasks.transform`); unless a rule is given, the edit then uses the
rule that scored best, and the summary says which and by how much."""
import json
import os
import time

import imageio.v3 as iio
import numpy as np

from .data import load_dataset
from .fit.config import FitConfig
from .fit.run import finished, run_fit
from .io.images import contact_sheet, display_to_uint8, write_png
from .io.run_folder import claim, staging
from .synth.make import make_dataset
from .tasks import run_task

EDITS = (("removal", {}), ("transform", {"use_dataset_transform": True}), ("camouflage", {}), ("nonneg", {}))
TURNTABLE_FRAMES = 36
TURNTABLE_LABELS = ("moved", "original")


def run_demo(out, scene, spp=128, progress=True, composition=None):
    """Returns a summary dict; everything lands under ``out``. ``composition``: the rule that moves
    the object (default: the best against the ground truth)."""
    name = os.path.splitext(os.path.basename(scene))[0]
    data, run = os.path.join(out, "data", name), os.path.join(out, "run", name)
    claim(out, "demo")  # the sheet and turntable are written straight into it
    timings = {}
    t = time.perf_counter()
    if not os.path.isfile(os.path.join(data, "transforms.json")):  # deterministic: reuse when present
        make_dataset(scene, data, spp=spp, progress=progress)
    timings["dataset"] = time.perf_counter() - t
    t = time.perf_counter()
    if finished(run, data, []):  # a finished fit of this dataset with the defaults (its edits live inside it)
        with open(os.path.join(run, "metrics.json")) as f:
            fit = json.load(f)
    else:  # a demo killed during its fit continues it (the staged job's dataset and settings are checked)
        resumable = os.path.isfile(os.path.join(staging(run), "checkpoints", "last.npz"))
        fit = run_fit(data, run, FitConfig(), resume=resumable, progress=progress)
    timings["fit"] = time.perf_counter() - t
    results = {}
    for task, options in EDITS:
        t = time.perf_counter()
        if task == "transform" and composition:
            options = {**options, "composition": composition}
        folder = run_task(run, task, options, progress=progress)
        results[task] = _metrics(folder)
        if task == "transform" and not composition:
            chosen = best_rule(results[task])
            if chosen and chosen != results[task]["composition"]:
                folder = run_task(run, task, {**options, "composition": chosen}, progress=progress)
                results[task] = _metrics(folder)
        timings[task] = time.perf_counter() - t
    sheet = os.path.join(out, f"{name}_contact_sheet.png")
    images, labels = _sheet_images(data, run)
    write_png(sheet, contact_sheet(images, columns=4, labels=labels))
    t = time.perf_counter()
    turntable = _turntable(run, out, name)
    timings["turntable"] = time.perf_counter() - t
    return {"dataset": data, "run": run, "contact_sheet": sheet, "turntable": turntable, "seconds": timings,
            "fit": fit["held_out"], "tasks": results, "composition": _rule_note(results["transform"], composition)}


def _metrics(folder):
    with open(os.path.join(folder, "metrics.json")) as f:
        return json.load(f)


def best_rule(transform_metrics):
    """The composition rule of highest PSNR against the moved ground truth, or None without one."""
    table = {k: v["psnr"] for k, v in transform_metrics.get("rules_vs_ground_truth", {}).items()
             if v.get("psnr") is not None}
    return max(table, key=table.get) if table else None


def _rule_note(m, given):
    table = m.get("rules_vs_ground_truth", {})
    used = m["composition"]
    score = table.get(used, {}).get("psnr")
    how = "as asked" if given else "the best of the rules against the ground truth"
    scores = ", ".join(f"{k} {v['psnr']:.2f}" for k, v in table.items() if v.get("psnr") is not None)
    return f"object moved with composition rule '{used}' ({how}; PSNR {score:.2f} dB; all: {scores})" \
        if score is not None else f"object moved with composition rule '{used}' (no ground truth to compare)"


def _turntable(run, out, name):
    """An orbit of the moved object (left) beside the original scene (right: the full field), as a video;
    each panel captioned (:data:`TURNTABLE_LABELS`) on a white band above it."""
    from .api import Edit, load_run
    from .camera_paths import make_path
    from .video import write_video
    fitted = load_run(run)
    moved = Edit(os.path.join(run, "transform"), fitted.dataset)
    cams = make_path("orbit", [fitted.dataset.cameras[v] for v in fitted.dataset.train], TURNTABLE_FRAMES)
    frames = []
    for cam in cams:
        a = moved.render(cam, layers=("composite",), linear=False)["composite"]
        b = fitted.render(cam, layers=("full",), linear=False)["full"]  # the original: the full field
        frames.append(contact_sheet([_display(a), _display(b)], labels=TURNTABLE_LABELS))
    return write_video(os.path.join(out, f"{name}_turntable"), frames, fps=12)


def _display(rgba):
    return (np.clip(rgba[..., :3], 0, 1) * 255 + 0.5).astype(np.uint8)


SHEET = (("previews/view{v:03d}_full.png", "full scene"), ("previews/view{v:03d}_bg.png", "background"),
         ("previews/view{v:03d}_fg.png", "foreground"), ("transform/view{v:03d}_composite.png", "moved"),
         ("camouflage/view{v:03d}_composite.png", "camouflage"), ("nonneg/view{v:03d}_composite.png", "light only"),
         ("previews/view{v:03d}_depth.png", "depth"))


def _sheet_images(data, run):
    """First held-out view, labelled: photo, fit, background, foreground, moved, camouflage,
    light-only edit, depth."""
    ds = load_dataset(data)
    v = int(ds.test[0])
    images, labels = [display_to_uint8(ds.images[v])], ["photo"]
    for path, label in SHEET:
        p = os.path.join(run, path.format(v=v))
        images.append(iio.imread(p)[..., :3] if os.path.isfile(p) else np.zeros_like(images[0]))
        labels.append(label)
    return images, labels
