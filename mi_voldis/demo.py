"""The whole pipeline on a bundled scene: dataset -> fit -> disentangle -> edits -> EXRs and a contact sheet."""
import json
import os
import time

import imageio.v3 as iio
import numpy as np

from .data import load_dataset
from .fit.config import FitConfig
from .fit.run import run_fit
from .io.images import contact_sheet, display_to_uint8, write_png
from .synth.make import make_dataset
from .tasks import run_task

EDITS = (("removal", {}), ("transform", {"use_dataset_transform": True}), ("camouflage", {}), ("nonneg", {}))


def run_demo(out, scene, spp=128, progress=True):
    """Returns a summary dict; everything lands under ``out``."""
    name = os.path.splitext(os.path.basename(scene))[0]
    data, run = os.path.join(out, "data", name), os.path.join(out, "run", name)
    timings = {}
    t = time.perf_counter()
    if not os.path.isfile(os.path.join(data, "transforms.json")):  # deterministic: reuse when present
        make_dataset(scene, data, spp=spp, progress=progress)
    timings["dataset"] = time.perf_counter() - t
    t = time.perf_counter()
    fit = run_fit(data, run, FitConfig(), progress=progress)
    timings["fit"] = time.perf_counter() - t
    results = {}
    for task, options in EDITS:
        t = time.perf_counter()
        folder = run_task(run, task, options, progress=progress)
        timings[task] = time.perf_counter() - t
        with open(os.path.join(folder, "metrics.json")) as f:
            results[task] = json.load(f)
    sheet = os.path.join(out, f"{name}_contact_sheet.png")
    write_png(sheet, contact_sheet(_sheet_images(data, run), columns=4))
    return {"dataset": data, "run": run, "contact_sheet": sheet, "seconds": timings,
            "fit": fit["held_out"], "tasks": results}


def _sheet_images(data, run):
    """First held-out view: photo, fit, background, foreground / moved, camouflage, light-only edit."""
    ds = load_dataset(data)
    v = int(ds.test[0])
    row = [display_to_uint8(ds.images[v])]
    for path in (f"previews/view{v:03d}_full.png", f"previews/view{v:03d}_bg.png", f"previews/view{v:03d}_fg.png",
                 f"transform/view{v:03d}_composite.png", f"camouflage/view{v:03d}_composite.png",
                 f"nonneg/view{v:03d}_composite.png", f"previews/view{v:03d}_depth.png"):
        p = os.path.join(run, path)
        row.append(iio.imread(p)[..., :3] if os.path.isfile(p) else np.zeros_like(row[0]))
    return row
