"""The benchmark: speed against error, side by side, in one process tree; writes reports/bench.md.

Sections (each a function returning rows for the report):
1. ray-marcher throughput of the brick grid, the dense grid and a PyTorch implementation of the brick
   grid, same run; machine bandwidth, bytes per sample and the bound they set;
2. held-out PSNR against wall-clock seconds of the default command on every bundled scene and real
   capture (and the dense grid beside it on some); evaluated samples per ray, run-folder size;
3. cost against scene content (small / large box, occupancy on / off);
4. removal by background strategy on the bundled and random ground-truth scenes, beside OpenCV's 2D
   inpainting (its own report, reports/removal.md: ``scripts/bench.py --removal``);
5. accuracy against ground truth on the bundled scenes (removal vs OpenCV, moved object per
   composition rule, foreground coverage), and every task on the real statue capture.
Fits and tasks run as child processes (scripts/train.py, scripts/optimize.py), which also gives
their peak RSS.
"""
import json
import os
import re
import shutil
import subprocess
import sys
import time

from ..io.run_folder import made_by
from ..synth import bundled_scene, family
from . import content, machine, rays, throughput
from .strategies import BACKGROUND_SETTINGS

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the checkout, or site-packages
# the real captures (README's data): $MI_VOLDIS_CAPTURES, else ../shared/data beside the checkout
SHARED = os.environ.get("MI_VOLDIS_CAPTURES") or os.path.join(os.path.dirname(ROOT), "shared", "data")


def present(captures, scenes=None, announce=True):
    """The real captures of ``captures`` (among ``scenes`` if given) found in SHARED; with ``announce``
    each one missing is named on stderr, as the benchmark then skips it (once: when the command's
    scenes are checked, :func:`section_scenes`)."""
    wanted = [c for c in captures if not scenes or c in scenes]
    for c in wanted if announce else ():
        if not os.path.isdir(os.path.join(SHARED, c)):
            print(f"bench: skipping {c}: no {os.path.join(SHARED, c)} (set MI_VOLDIS_CAPTURES)", file=sys.stderr)
    return [c for c in wanted if os.path.isdir(os.path.join(SHARED, c))]


def section_scenes(section, scenes=None):
    """The scenes a section ("all", "quick", "removal", "masks", "effects", "family", "spinnerf") would run, of
    ``scenes`` if given (the real captures only where present; "spinnerf" offers the family and runs its check
    half by default). Raises ValueError naming an unknown scene, or when nothing is left to run (then no report
    is written over the last one)."""
    captures = {"all": CAPTURES, "quick": [], "removal": REMOVAL_CAPTURES, "masks": [], "effects": [],
                "family": [], "spinnerf": []}[section]
    family_scenes = [family.name(k) for k in range(family.SIZE)]
    offered = {"all": SCENES, "quick": SCENES[:1], "family": family_scenes,
               "spinnerf": family_scenes}.get(section, TRUTH_SCENES) + captures
    unknown = [s for s in scenes or [] if s not in offered]
    if unknown:
        raise ValueError(f"--scenes: {', '.join(unknown)} not among this section's scenes ({', '.join(offered)})")
    if section == "spinnerf" and not scenes:  # judged where nothing was tuned: the family's check half
        scenes = [family.name(k) for k in family.CHECK]
    run = [s for s in offered if s not in captures and (not scenes or s in scenes)] + present(captures, scenes)
    if not run:
        raise ValueError(f"--scenes: nothing to run (the captures are read from {SHARED}; set MI_VOLDIS_CAPTURES)")
    return run


def child(args, log_file=None):
    """Run a child Python process; returns its wall-clock seconds. Raises on failure. (Children report
    their own peak memory in metrics.json: ``ru_maxrss`` of a forked child includes the parent's.) A
    script runs on this process's variant (its ``--variant`` would otherwise default to llvm_ad_rgb).
    ``scripts/NAME.py`` (as the report states the command) runs as ``python -m voldis_cli NAME``, the same
    program, which an installed package has without the scripts; the children start in ROOT, the folder
    that holds this package, so that ``-m`` imports this copy of it."""
    import mitsuba as mi
    command = list(args)
    if args[0].endswith(".py"):
        command = ["-m", "voldis_cli", os.path.basename(args[0])[:-3]] + args[1:] + ["--variant", mi.variant()]
    t = time.perf_counter()
    with open(log_file or os.devnull, "w") as log:
        status = subprocess.run([sys.executable] + command, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT).returncode
    if status != 0:
        raise RuntimeError(f"{' '.join(args)} failed (status {status}); see {log_file}")
    return time.perf_counter() - t


# ------------------------------------------------------------------------------------ 1. throughput
# (grid vertices per side, samples per ray, rays per batch); every row runs the brick grid (every brick
# allocated), the dense grid, the brick grid with a view lattice and PyTorch's brick grid side by side
THROUGHPUT_ROWS = [(128, 128, 16384), (256, 128, 16384), (128, 64, 16384), (128, 256, 16384), (128, 128, 65536)]
QUICK_THROUGHPUT_ROWS = [(64, 64, 4096)]


def run_throughput(quick):
    """Rows of THROUGHPUT_ROWS on random rays, the first also on tiled (coherent) rays: voldis bricks,
    voldis dense, voldis bricks with a view lattice (grey degree 1's default) and the PyTorch reference of
    the brick grid, in alternating blocks of steps."""
    sizes = QUICK_THROUGHPUT_ROWS if quick else THROUGHPUT_ROWS
    try:
        from . import torch_reference
    except ImportError:
        torch_reference = None
    rows = []
    for k, (r, n, b) in enumerate(sizes):
        for kind in rays.KINDS if k == 0 else ("random",):
            heavy = r == 256 or b == 65536
            impls = {"voldis": throughput.step_functions(r, n, b, rays=kind, representation="bricks"),
                     "voldis_dense": throughput.step_functions(r, n, b, rays=kind, representation="dense"),
                     "voldis_view": throughput.step_functions(r, n, b, rays=kind, representation="view")}
            if torch_reference is not None:
                impls["torch"] = torch_reference.step_functions(r, n, b, rays=kind, representation="bricks")
            timed = throughput.interleaved(impls, 4 if heavy else 6,
                                           {"voldis": 2, "voldis_dense": 2, "voldis_view": 2, "torch": 1})
            rows.append({"resolution": r, "samples": n, "batch": b, "rays": kind, **timed})
            del impls  # free the grids before the next row
    return rows


# ---------------------------------------------------------------------------- 2. speed vs error
# Every scene is fitted with the default command (no setting); "dense" rows keep every brick (carve=false,
# today's dense grid at the same schedule) to compare the representations; the NDC row is the fixed
# per-scene configuration fern needed before resolutions were derived from the capture.
SCENES = ["tabletop", "room"]  # bundled (rendered by scripts/make_dataset.py)
RANDOM_SEEDS = [0, 1, 2, 3, 4]  # random scenes (make_dataset.py --random): the first five, fixed before any result
TRUTH_SCENES = SCENES + [f"random{k}" for k in RANDOM_SEEDS]  # the scenes with ground truth
CAPTURES = ["fern", "horns", "statue", "garden", "lego_200"]  # ../shared/data; skipped when absent
VARIANTS = {
    "tabletop": {"dense (carve=false)": ["carve=false"]},
    "fern": {"NDC (space=ndc, as the peers fit LLFF)": ["space=\"ndc\""]},
}
QUICK_SETS = ["minutes=null", "steps_full=200", "steps_bg=40", "resolution_schedule=[[0,32],[80,64]]",
              "sh_degree=0", "occupancy_at_step=80", "eval_every=50"]


def fit(dataset, out, sets, log_dir, keep=False):
    """Fit ``dataset`` into ``out`` with the ``--set`` overrides ``sets``; a finished run of the same
    dataset and settings already in ``out`` is reused (delete it to fit again). ``keep``: the run keeps
    its final checkpoint (the removal section refits the background from it, so that settings of the
    background alone may differ)."""
    from ..fit.run import finished
    args = ["scripts/train.py", dataset, "--out", out, "--quiet"] + (["--keep-checkpoints"] if keep else [])
    for s in sets:
        args += ["--set", s]
    kept = os.path.isfile(os.path.join(out, "checkpoints", "last.npz"))
    if finished(out, dataset, sets, BACKGROUND_SETTINGS if keep else ()) and (not keep or kept):
        seconds = None
    else:
        seconds = child(args, os.path.join(log_dir, os.path.basename(out) + ".log"))
    with open(os.path.join(out, "metrics.json")) as f:
        metrics = json.load(f)
    with open(os.path.join(out, "log.json")) as f:
        log = json.load(f)
    curve = [(r["time"], r["test_psnr"]) for r in log if "test_psnr" in r]
    return {"out": out, "wall_seconds": seconds, "rss_mib": metrics.get("peak_rss_mib"), "metrics": metrics,
            "curve": curve, "folder_mib": folder_bytes(out) / 2 ** 20, "command": "python " + " ".join(args),
            "reused": seconds is None, "fitted": time.strftime("%Y-%m-%d %H:%M", time.gmtime(os.path.getmtime(
                os.path.join(out, "metrics.json"))))}


def folder_bytes(path):
    """Bytes of the run folder as the default command leaves it: without ``checkpoints/`` (kept only
    with ``--keep-checkpoints``) and without task folders written into it later (those hold their own
    ``scene.xml``)."""
    total = 0
    for d, dirs, files in os.walk(path):
        dirs[:] = [s for s in dirs if s != "checkpoints" and not os.path.isfile(os.path.join(d, s, "scene.xml"))]
        total += sum(os.path.getsize(os.path.join(d, f)) for f in files)
    return total


def time_to_within(curve, best, tolerance=0.5):
    return next((t for t, p in curve if p >= best - tolerance), None)


def make_data(scene, out, log_dir, quick, layout="transforms"):
    """A bundled scene's dataset, or (``scene`` 'random<SEED>') a random scene's, rendered once; ``layout``
    'spinnerf': in SPIn-NeRF's LLFF layout (``make_dataset.py --layout spinnerf``)."""
    # a file every dataset of that layout has (make_dataset swaps the folder into place only when complete)
    done = "poses_bounds.npy" if layout == "spinnerf" else "transforms.json"
    if not os.path.isfile(os.path.join(out, done)):
        k = family.index(scene)
        source = ["--family", str(k)] if k is not None else \
            ["--random", scene[len("random"):]] if scene.startswith("random") else [bundled_scene(scene)]
        args = ["scripts/make_dataset.py"] + source + ["--out", out]
        if layout != "transforms":
            args += ["--layout", layout]
        if quick:
            args += ["--views", "24", "--spp", "32"]
        child(args, os.path.join(log_dir, f"data_{scene}{'' if layout == 'transforms' else '_' + layout}.log"))
    return out


# ------------------------------------------------------------------------------------ 4. removal
# bg_strategy values compared from one fitted full field; "STRATEGY+SETTING" / "STRATEGY-SETTING": with that
# boolean setting on / off; "STRATEGY+SETTING=VALUE": with that value
STRATEGIES = ["lift", "clear", "harmonic", "guided", "guided+shadow_contrast=0", "guided-keep_seen",
              "guided+keep_seen_gap=0", "guided+keep_seen_gap=4"]


def ground_truth_fits(work, scenes, results, among=None, sets=()):
    """(scene, dataset, default fit kept with its checkpoint, logs folder) of every ground-truth scene
    of ``among`` (default: bundled and random; ``scenes`` picks some), made when missing; ``sets``:
    ``--set`` overrides of the fits (a trial of a default); ``results['seconds']`` is set when the loop ends."""
    logs = os.path.join(work, "logs")
    os.makedirs(logs, exist_ok=True)
    t0 = time.perf_counter()
    for scene in [s for s in among or TRUTH_SCENES if not scenes or s in scenes]:
        data = make_data(scene, os.path.join(work, "data", scene), logs, False)
        yield scene, data, fit(data, os.path.join(work, "runs", f"{scene}_0"), list(sets), logs, keep=True), logs
    results["seconds"] = time.perf_counter() - t0


def new_results():
    return {"machine": machine.describe(), "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "scenes": {}}


def save_results(results, report_dir, name):
    os.makedirs(report_dir, exist_ok=True)
    with open(os.path.join(report_dir, name), "w") as f:
        json.dump(results, f, indent=1, default=float)
    return results


# on captures without ground truth: the earlier default harmonic, the default and its variants
CAPTURE_STRATEGIES = ["harmonic", "guided", "guided-keep_seen", "guided+keep_seen_gap=0", "guided+keep_seen_gap=4"]
REMOVAL_CAPTURES = ["statue"]  # captures with object masks (../shared/data; skipped when absent)


def run_removal(work, report_dir, scenes=None):
    """Removal by background strategy on every ground-truth scene (bundled and random), each from the
    default command's full field (:mod:`mi_voldis.bench.strategies`), and on the captures with masks
    (consistency and previews of every held-out view); previews copied to ``report_dir``."""
    results = new_results()
    for scene, _, run, logs in ground_truth_fits(work, scenes, results):
        results["scenes"][scene] = {"fit": run, "strategies": strategy_rows(work, scene, run, STRATEGIES, logs)}
    t0, logs = time.perf_counter(), os.path.join(work, "logs")
    results["captures"] = {}
    for capture in present(REMOVAL_CAPTURES, scenes, announce=False):
        path = os.path.join(SHARED, capture)
        run = fit(path, os.path.join(work, "runs", f"{capture}_0"), [], logs, keep=True)
        results["captures"][capture] = {"fit": run,
                                        "strategies": strategy_rows(work, capture, run, CAPTURE_STRATEGIES, logs)}
    results["seconds"] = results.get("seconds", 0.0) + time.perf_counter() - t0
    return save_results(results, report_dir, "removal.json")


def strategy_switch(strategy):
    """A strategy row's ``bg_strategy`` and its extra arguments: "guided-object_front" ->
    ("guided", ["--set", "object_front=false"]), "guided+keep_seen_gap=0" -> ("guided", ["--set",
    "keep_seen_gap=0"])."""
    match = re.fullmatch(r"(\w+)(?:([+-])(\w+)|\+(\w+=[\w.]+))?", strategy)
    if match is None:
        raise ValueError(f"strategy row {strategy!r}: expected STRATEGY, STRATEGY+SETTING, STRATEGY-SETTING "
                         "or STRATEGY+SETTING=VALUE")
    name, sign, setting, assignment = match.groups()
    if assignment:
        return name, ["--set", assignment]
    return name, (["--set", f"{setting}={'true' if sign == '+' else 'false'}"] if setting else [])


def refitted_since(metrics, run):
    """``metrics`` (a strategy's metrics.json) was written after ``run``'s fit finished."""
    fitted = os.path.join(run, "metrics.json")
    return os.path.isfile(metrics) and os.path.getmtime(metrics) > os.path.getmtime(fitted)


def strategy_rows(work, scene, run, strategies, logs):
    """Each of ``strategies`` refitted from ``run``'s full field: its metrics, wall seconds and command.
    Always refitted (``--refit``): a run kept from before a change to the background phase's code holds
    a background today's code would not fit."""
    rows = {}
    for strategy in strategies:
        name, switch = strategy_switch(strategy)
        out = os.path.join(work, "removal", scene, strategy)
        args = ["-m", "mi_voldis.bench.strategies", run["out"], name, out, "--refit"] + switch
        done = os.path.join(out, "metrics.json")
        reuse = refitted_since(done, run["out"])  # a rerun after an interruption keeps what it finished
        wall = None if reuse else child(args, os.path.join(logs, f"removal_{scene}_{strategy}.log"))
        with open(done) as f:
            rows[strategy] = {**json.load(f), "wall_seconds": wall, "out": out, "command": "python " + " ".join(args)}
    run.pop("curve", None)
    return rows


def run_effects(work, report_dir, scenes=None):
    """The object's shadow as an input (:mod:`mi_voldis.bench.effects`) on every ground-truth scene, from
    the removal section's fits (made here when missing)."""
    results = new_results()
    for scene, _, run, logs in ground_truth_fits(work, scenes, results):
        out = os.path.join(work, "effects", scene)
        args = ["-m", "mi_voldis.bench.effects", run["out"], out]
        wall = child(args, os.path.join(logs, f"effects_{scene}.log"))
        with open(os.path.join(out, "metrics.json")) as f:
            results["scenes"][scene] = {**json.load(f), "wall_seconds": wall, "out": out,
                                        "command": "python " + " ".join(args)}
    return save_results(results, report_dir, "effects.json")


def run_masks(work, report_dir, scenes=None):
    """Masks from two views on every ground-truth scene (:mod:`mi_voldis.bench.masks`), from the removal
    section's fits (made here when missing), beside the removal with every ground-truth mask."""
    from ..fit.config import FitConfig
    results = new_results()
    for scene, data, run, logs in ground_truth_fits(work, scenes, results):
        default = FitConfig().bg_strategy  # the made masks' removal uses it too (mi_voldis.bench.masks)
        base = os.path.join(work, "removal", scene, default)
        if not os.path.isfile(os.path.join(base, "metrics.json")):
            child(["-m", "mi_voldis.bench.strategies", run["out"], default, base, "--refit"],
                  os.path.join(logs, f"removal_{scene}_{default}.log"))
        out = os.path.join(work, "masks", scene)
        if made_by(out) == {"bench_masks"}:  # an earlier run's, made afresh; anything else is refused (bench.masks)
            shutil.rmtree(out)
        args = ["-m", "mi_voldis.bench.masks", run["out"], out]
        wall = child(args, os.path.join(logs, f"masks_{scene}.log"))
        with open(os.path.join(out, "metrics.json")) as f:
            row = json.load(f)
        with open(os.path.join(out, "removal", "metrics.json")) as f:
            row["removal"] = json.load(f)
        with open(os.path.join(base, "metrics.json")) as f:
            row["removal_true_masks"] = json.load(f)
        results["scenes"][scene] = {**row, "wall_seconds": wall, "out": out, "data": data,
                                    "command": "python " + " ".join(args)}
    return save_results(results, report_dir, "masks.json")


# ------------------------------------------------------------------------------------ 5. accuracy
def task(run, name, extra, log_dir):
    args = ["scripts/optimize.py", run, "--task", name, "--quiet"] + extra
    seconds = child(args, os.path.join(log_dir, f"{os.path.basename(run)}_{name}.log"))
    with open(os.path.join(run, name, "metrics.json")) as f:
        metrics = json.load(f)
    return {"run": run, "seconds": seconds, "rss_mib": metrics.get("peak_rss_mib"), "metrics": metrics,
            "command": "python " + " ".join(args)}


def run_all(quick, work, report_dir, scenes=None):
    """Every section; ``scenes``: only these scenes' fits and tasks (default: all)."""
    logs = os.path.join(work, "logs")
    os.makedirs(logs, exist_ok=True)
    results = {"machine": machine.describe(), "bandwidth": machine.copy_bandwidth(0.5 if quick else 2.0),
               "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "quick": quick}
    t0 = time.perf_counter()
    results["throughput"] = run_throughput(quick)
    results["content"] = [content.measure(size, occ) for size in ((1.2, 2.4) if quick else (1.2, 3.6))
                          for occ in (False, True)]
    fits = {}
    datasets = {scene: make_data(scene, os.path.join(work, "data", scene), logs, quick)
                for scene in (SCENES[:1] if quick else SCENES)
                if not scenes or scene in scenes}
    if not quick:
        datasets.update({c: os.path.join(SHARED, c) for c in present(CAPTURES, scenes, announce=False)})
    if scenes:
        datasets = {k: v for k, v in datasets.items() if k in scenes}
    for scene, path in datasets.items():
        configs = {"default": QUICK_SETS if quick else []}
        if not quick:
            configs.update(VARIANTS.get(scene, {}))
        for k, (name, sets) in enumerate(configs.items()):
            fits[f"{scene}: {name}"] = fit(path, os.path.join(work, "runs", f"{scene}_{k}"), sets, logs)
    results["fits"] = fits
    os.makedirs(report_dir, exist_ok=True)
    from .offpath import offpath_sheet
    results["offpath"] = {scene: os.path.basename(offpath_sheet(fits[f"{scene}: default"]["out"], path, os.path.join(
        report_dir, f"{scene}_offpath.png"))) for scene, path in datasets.items()}
    tasks = {}
    runs = {scene: fits[f"{scene}: default"]["out"] for scene in ("tabletop", "statue") if f"{scene}: default" in fits}
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

