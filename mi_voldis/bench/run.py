"""The benchmark: speed against error, side by side, in one process tree; writes reports/bench.md.

Sections (each a function returning rows for the report):
1. ray-marcher throughput of the voldis path and of the PyTorch grid_sample reference, same run;
   machine bandwidth and the bound it sets;
2. held-out PSNR against wall-clock seconds while fitting, several grid resolutions and sample
   spacings, on a bundled scene and on fern; time to within 0.5 dB of the best;
3. cost against scene content (small / large box, occupancy on / off);
4. accuracy against ground truth on the bundled scenes (removal vs OpenCV, moved object per
   composition rule, foreground coverage), and every task on the real statue capture;
5. peak memory (RSS) of each fit.
Fits and tasks run as child processes (scripts/train.py, scripts/optimize.py), which also gives
their peak RSS.
"""
import json
import os
import subprocess
import sys
import time

from . import content, machine, rays, throughput

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SHARED = os.path.join(os.path.dirname(ROOT), "shared", "data")


def child(args, log_file=None):
    """Run a child Python process; returns its wall-clock seconds. Raises on failure. (Children report
    their own peak memory in metrics.json: ``ru_maxrss`` of a forked child includes the parent's.)"""
    t = time.perf_counter()
    with open(log_file or os.devnull, "w") as log:
        status = subprocess.run([sys.executable] + args, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT).returncode
    if status != 0:
        raise RuntimeError(f"{' '.join(args)} failed (status {status}); see {log_file}")
    return time.perf_counter() - t


# ------------------------------------------------------------------------------------ 1. throughput
def run_throughput(quick):
    """Rows (resolution, samples, batch, ray kind): every combination on random rays, and the rows
    with 128 samples per ray also on tiled (coherent) rays; PyTorch on the rows with 128 samples."""
    sizes = [(128, 128, 16384)] if quick else [(r, n, b) for r in (64, 128, 256) for n in (64, 128, 256)
                                               for b in (4096, 16384, 65536)]
    try:
        from . import torch_reference
    except ImportError:
        torch_reference = None
    rows = []
    for r, n, b in sizes:
        for kind in rays.KINDS if n == 128 else ("random",):
            heavy = r == 256 or b == 65536
            impls = {"voldis": throughput.step_functions(r, n, b, rays=kind)}
            if torch_reference is not None and n == 128:
                impls["torch"] = torch_reference.step_functions(r, n, b, rays=kind)
            timed = throughput.interleaved(impls, 4 if heavy else 6, {"voldis": 2, "torch": 1})
            rows.append({"resolution": r, "samples": n, "batch": b, "rays": kind, **timed})
            del impls  # free both implementations' grids before the next row
    return rows


# ---------------------------------------------------------------------------- 2. speed vs error
TABLETOP_CONFIGS = {  # name: --set overrides of the fitting configuration
    "96 vox, 0.5 step": ["resolution_schedule=[[0,48],[250,72],[500,96]]"],
    "128 vox, 0.5 step (default)": [],
    "160 vox, 0.5 step": ["resolution_schedule=[[0,48],[250,96],[500,160]]"],
    "128 vox, 1.0 step": ["step_voxels=1.0"],
    "128 vox, 0.5 step, 4 x 4 ray tiles": ["batch_tile=4"],
    "128 vox, 0.5 step, SH degree 1 (forced)": ["sh_degree=1"],
}
FERN_CONFIGS = {"192 vox (NDC), 0.5 step": ["resolution_schedule=[[0,64],[300,128],[700,192]]", "steps_full=1400",
                                            "tighten_at_step=300"]}
QUICK_SETS = ["steps_full=200", "steps_bg=40", "resolution_schedule=[[0,32],[80,64]]", "tighten_at_step=80",
              "sh_degree=0"]


def fit(dataset, out, sets, log_dir):
    args = ["scripts/train.py", dataset, "--out", out, "--quiet", "--set", "eval_every=100"]
    for s in sets:
        args += ["--set", s]
    seconds = child(args, os.path.join(log_dir, os.path.basename(out) + ".log"))
    with open(os.path.join(out, "metrics.json")) as f:
        metrics = json.load(f)
    with open(os.path.join(out, "log.json")) as f:
        log = json.load(f)
    curve = [(r["time"], r["test_psnr"]) for r in log if "test_psnr" in r]
    return {"out": out, "wall_seconds": seconds, "rss_mib": metrics.get("peak_rss_mib"), "metrics": metrics,
            "curve": curve, "command": "python " + " ".join(args)}


def time_to_within(curve, best, tolerance=0.5):
    return next((t for t, p in curve if p >= best - tolerance), None)


def make_data(scene, out, log_dir, quick):
    if not os.path.isfile(os.path.join(out, "transforms.json")):
        args = ["scripts/make_dataset.py", os.path.join("scenes", scene + ".xml"), "--out", out]
        if quick:
            args += ["--views", "24", "--spp", "32"]
        child(args, os.path.join(log_dir, f"data_{scene}.log"))
    return out


# ------------------------------------------------------------------------------------ 4. accuracy
def task(run, name, extra, log_dir):
    args = ["scripts/optimize.py", run, "--task", name, "--quiet"] + extra
    seconds = child(args, os.path.join(log_dir, f"{os.path.basename(run)}_{name}.log"))
    with open(os.path.join(run, name, "metrics.json")) as f:
        metrics = json.load(f)
    return {"run": run, "seconds": seconds, "rss_mib": metrics.get("peak_rss_mib"), "metrics": metrics,
            "command": "python " + " ".join(args)}


def run_all(quick, work, report_dir):
    logs = os.path.join(work, "logs")
    os.makedirs(logs, exist_ok=True)
    results = {"machine": machine.describe(), "bandwidth": machine.copy_bandwidth(0.5 if quick else 2.0),
               "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "quick": quick}
    t0 = time.perf_counter()
    results["throughput"] = run_throughput(quick)
    results["content"] = [content.measure(size, occ) for size in ((1.2, 2.4) if quick else (1.2, 3.6))
                          for occ in (False, True)]
    tabletop = make_data("tabletop", os.path.join(work, "data", "tabletop"), logs, quick)
    fits = {}
    configs = {"quick": QUICK_SETS} if quick else TABLETOP_CONFIGS
    for k, (name, sets) in enumerate(configs.items()):
        fits[f"tabletop: {name}"] = fit(tabletop, os.path.join(work, "runs", f"tabletop_{k}"), sets, logs)
    main_run = next(iter(fits.values()))["out"] if quick else fits["tabletop: 128 vox, 0.5 step (default)"]["out"]
    fits_scratch = fit(tabletop, os.path.join(work, "runs", "tabletop_scratch"),
                       (QUICK_SETS if quick else []) + ["bg_strategy=\"scratch\""], logs)
    fits["tabletop: background from scratch"] = fits_scratch
    if not quick:
        if os.path.isdir(os.path.join(SHARED, "fern")):
            for k, (name, sets) in enumerate(FERN_CONFIGS.items()):
                fits[f"fern: {name}"] = fit(os.path.join(SHARED, "fern"), os.path.join(work, "runs", f"fern_{k}"),
                                            sets, logs)
        room = make_data("room", os.path.join(work, "data", "room"), logs, quick)
        fits["room: default"] = fit(room, os.path.join(work, "runs", "room"), [], logs)
        statue = os.path.join(SHARED, "statue")
        if os.path.isdir(statue):
            fits["statue: default"] = fit(statue, os.path.join(work, "runs", "statue"), [], logs)
    results["fits"] = fits
    tasks = {}
    runs = {"tabletop": main_run}
    if not quick:
        runs["room"] = fits["room: default"]["out"]
        if "statue: default" in fits:
            runs["statue"] = fits["statue: default"]["out"]
    for scene, run in runs.items():
        steps = ["--steps", "60"] if quick else []
        tasks[scene] = {
            "removal": task(run, "removal", [], logs),
            "transform": task(run, "transform", ["--dataset-transform"] if scene != "statue" else
                              ["--translate", "0.1,0,0", "--rotate", "y:20"], logs),
            "camouflage": task(run, "camouflage", steps, logs),
            "nonneg": task(run, "nonneg", steps, logs),
        }
    results["tasks"] = tasks
    results["seconds"] = time.perf_counter() - t0
    os.makedirs(report_dir, exist_ok=True)
    with open(os.path.join(report_dir, "bench.json"), "w") as f:
        json.dump(results, f, indent=1, default=float)
    return results


def msps_bound(bandwidth_gbs, bytes_per_sample):
    return bandwidth_gbs * 1e9 / bytes_per_sample / 1e6

