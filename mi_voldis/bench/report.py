"""reports/bench.md and its plots, from the results of :func:`mi_voldis.bench.run.run_all`."""
import os
import shutil

from ..inpaint2d import BASELINES, available_baselines
from . import rays
from .machine import BYTES_FORWARD, BYTES_TABLE, BYTES_TRAIN
from .run import msps_bound, time_to_within


def _f(x, digits=1):
    return "-" if x is None or x != x else f"{x:.{digits}f}"  # None or NaN


def write(results, report_dir, command):
    os.makedirs(report_dir, exist_ok=True)
    md = [f"# mi-voldis benchmark{' (quick)' if results['quick'] else ''}", "",
          f"Run {results['date']} with `{command}` ({results['seconds'] / 60:.1f} min).", ""]
    m = results["machine"]
    md += [f"Machine: {m['cpu']}, {m['cores']} cores, {m['system']}; variant `{m['variant']}`; "
           + ", ".join(f"{k} {v}" for k, v in m["versions"].items()) + ".", "",
           "Timings are medians of a few steps on a shared machine (expect +-30% between runs). In a throughput "
           "row Dr.Jit and PyTorch run in alternating blocks of steps (two of each), so both see the same load "
           "and the ratio holds better than either figure.", ""]
    md += _throughput(results)
    md += _speed_error(results, report_dir)
    md += _content(results)
    md += _accuracy(results, report_dir)
    with open(os.path.join(report_dir, "bench.md"), "w") as f:
        f.write("\n".join(md) + "\n")


def _throughput(results):
    bw = results["bandwidth"]["drjit_gbs"]
    tile = rays.TILE
    bytes_b = {"forward": BYTES_FORWARD + BYTES_TABLE, "train": BYTES_TRAIN + 2 * BYTES_TABLE}
    bytes_d = {"forward": BYTES_FORWARD, "train": BYTES_TRAIN}
    md = ["## 1. Ray-marcher throughput: brick grid, dense grid, PyTorch", "",
          f"Memory bandwidth (large copy): {bw:.1f} GB/s with Dr.Jit on all cores, "
          f"{results['bandwidth']['numpy_gbs']:.1f} GB/s with NumPy on one. A dense sample touches "
          f"{BYTES_FORWARD} B forward (8 corners x 4 floats) and {BYTES_TRAIN} B in training (lookup, gradient "
          "read-modify-write, and the 16-byte record of the lookup written and read back); a brick sample adds "
          f"the 8 table reads ({BYTES_TABLE} B) to the lookup and to the gradient scatter: {bytes_b['forward']} B "
          f"and {bytes_b['train']} B. '% of bound' is the training rate over bandwidth / bytes per sample "
          "(bytes counted as if streamed; the lookups and scatters are scattered 16-byte accesses).", "",
          "Every row holds the same random field (raw density normal(-1, 1)) as a brick grid with every brick "
          "allocated (`voldis`, what fitting uses), as a dense grid (`dense`), and in PyTorch "
          "(`mi_voldis/bench/torch_reference.py`: the same brick grid, table lookups and trilinear weights in "
          "tensor code, autograd, `torch.optim.Adam`); the three run in alternating blocks of steps. The "
          "training step is fitting's: forward, backward, Adam on the packed grid. Rays "
          f"(`mi_voldis/bench/rays.py`): *random* rays, and *tiles* of {tile} x {tile} pixels of random views.",
          "", "*view step cost*: the training step's seconds with a 64^3 view lattice (grey degree-1 colour's "
          "default, `sh_view_resolution`) over the same brick grid's without one, run in the same blocks: an upper "
          "bound on the fit plan's `VIEW_STEP_COST` (`mi_voldis/fit/schedule.py`), which fits measure lower "
          "(`reports/notes.md`).",
          "", "| grid | samples/ray | batch | rays | bricks fwd Msps | bricks train Msps | % of bound | dense train "
          "Msps | dense % of bound | view step cost | torch train Msps | bricks / torch |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for row in results["throughput"]:
        v, d, t, w = row["voldis"], row.get("voldis_dense"), row.get("torch"), row.get("voldis_view")
        ratio = v["train"]["msps"] / t["train"]["msps"] if t else None
        view = w["train"]["seconds"] / v["train"]["seconds"] if w else None
        bound_b, bound_d = msps_bound(bw, bytes_b["train"]), msps_bound(bw, bytes_d["train"])
        md.append(f"| {row['resolution']}^3 | {row['samples']} | {row['batch']} | {row.get('rays', 'random')} | "
                  f"{v['forward']['msps']:.1f} | {v['train']['msps']:.1f} | "
                  f"{100 * v['train']['msps'] / bound_b:.0f}% | {_f(d and d['train']['msps'])} | "
                  f"{_f(d and 100 * d['train']['msps'] / bound_d, 0)}% | {_f(view, 2)}x | "
                  f"{_f(t and t['train']['msps'], 2)} | "
                  f"{_f(ratio)}x |")
    return md + [""]


def _speed_error(results, report_dir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fits = {k: v for k, v in results["fits"].items() if v["curve"]}
    fig, ax = plt.subplots(1, 1, figsize=(7, 4))
    for name, f in fits.items():
        t, p = zip(*f["curve"])
        ax.plot(t, p, "o-", ms=3, lw=1, label=name)
    ax.set_xlabel("fitting wall-clock seconds")
    ax.set_ylabel("held-out PSNR (dB), full field")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(report_dir, "speed_vs_error.png"), dpi=110)
    plt.close(fig)
    md = ["## 2. Speed against error (fitting)", "",
          "Every scene with the default command (`python scripts/train.py DATASET --out RUN`, no setting): the "
          "time budget, resolution and schedule come from the capture (`mi_voldis/fit/schedule.py`). *dense* "
          "rows keep every brick (`carve=false`). Every 8th view held out; PSNR of the full field.", "",
          "![speed vs error](speed_vs_error.png)", "",
          "| run | held-out PSNR | SSIM | budget min | fit s | to within 0.5 dB of best, s | final grid (capture asks) "
          "| bricks kept | evaluated samples/ray (held-out renders) | peak RSS MiB | run folder MB | SH |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, f in results["fits"].items():
        m = f["metrics"]
        best = max((p for _, p in f["curve"]), default=None)
        within = time_to_within(f["curve"], best) if best else None
        plan = (m.get("schedule") or {}).get("plan") or {}
        bricks = m.get("bricks", {}).get("full")
        kept = f"{100 * bricks['allocated'] / bricks['of']:.0f}%" if bricks else "-"
        md.append(f"| {name} | {m['held_out']['psnr']:.2f} | {m['held_out']['ssim']:.3f} | "
                  f"{_f(plan.get('minutes'))} | {m['seconds']['fit']:.0f} | {_f(within, 0)} | "
                  f"{'x'.join(map(str, m['grid']['full']))} ({plan.get('capture_resolution', '-')}) | {kept} | "
                  f"{_f(m['evaluated_samples_per_ray'], 0)} | {_f(f['rss_mib'], 0)} | "
                  f"{_f(f.get('folder_mib'), 0)} | {m['sh_degree']} |")
    if results.get("offpath"):
        md += ["", "Views off the training path (`mi_voldis/bench/offpath.py`): photo, held-out view, then that view "
               "moved lower, closer, and lower with a 1.5x wider field of view (space no training view saw stays "
               "empty, i.e. black):", ""]
        md += [f"![{scene} off-path views]({png})" for scene, png in results["offpath"].items()]
    md += ["", "Commands:", ""] + [f"- {name}: `{f['command']}`" + (f" (reused: fitted {f['fitted']} UTC by an earlier "
                                                                        "run of the benchmark in the same work folder)"
                                                                        if f.get("reused") else "")
                                   for name, f in results["fits"].items()]
    return md + [""]


def _content(results):
    md = ["## 3. Cost against scene content", "",
          "A sphere (r = 0.4) on a grid of 0.02 voxels filling a box of side 1.2 or 3.6; samples every half "
          "voxel; forward + backward of 8192 rays aimed at it.", "",
          "| box side | occupancy skipping | occupied cells | loop iterations/ray | evaluated samples/ray | "
          "seconds/step |", "|---|---|---|---|---|---|"]
    for r in results["content"]:
        md.append(f"| {r['size']} | {'on' if r['occupancy'] else 'off'} | {100 * r['occupied_fraction']:.1f}% | "
                  f"{r['iterations_per_ray']:.0f} | {r['evaluated_per_ray']:.0f} | {r['seconds']:.3f} |")
    return md + [""]


def _accuracy(results, report_dir):
    md = ["## 4. Accuracy against ground truth and the edits", ""]
    for scene, tasks in results["tasks"].items():
        md += [f"### {scene}", ""]
        removal = tasks["removal"]["metrics"]
        if "methods" in removal:
            md += ["| removal (in-mask = masks dilated by 3% of the diagonal) | PSNR in mask | SSIM in mask | "
                   "PSNR whole | view consistency PSNR | object residue |", "|---|---|---|---|---|---|"]
            labels = {"volume": "background volume (ours)", **BASELINES}
            for name, r in removal["methods"].items():
                label = labels.get(name, name)
                md.append(f"| {label} | {_f(r['psnr_mask'], 2)} | {_f(r['ssim_mask'], 3)} | {_f(r['psnr'], 2)} | "
                          f"{_f(r['consistency_psnr'], 2)} | {_f(r.get('residue'), 3)} |")
            md += ["", "Object residue: the share of the object's pixels whose removal is closer to the object's "
                   "own colour than to the true background (0: no trace of the object; "
                   "`mi_voldis.metrics.object_residue`).", ""]
        if "transform" not in tasks:  # random scenes: removal only
            continue
        tr = tasks["transform"]["metrics"]
        if tr.get("ground_truth"):
            md += ["| moved object, rule | PSNR vs ground truth | SSIM |", "|---|---|---|"]
            md += [f"| {rule} | {_f(r['psnr'], 2)} | {_f(r['ssim'], 3)} |"
                   for rule, r in tr["rules_vs_ground_truth"].items()]
            md.append("")
        cam, nn = tasks["camouflage"]["metrics"], tasks["nonneg"]["metrics"]
        md += [f"Camouflage: composite vs background render {cam['psnr_to_background_before']:.2f} -> "
               f"{cam['psnr_to_background_after']:.2f} dB, largest depth change {cam['max_depth_change']:g}.",
               f"Non-negative: full + residual vs background {nn['psnr_before']:.2f} -> {nn['psnr_after']:.2f} dB; "
               f"where the background is darker than the scene ({100 * nn['fraction_bg_darker']:.0f}% of pixels) "
               f"{nn['psnr_before_where_bg_darker']:.2f} -> {nn['psnr_after_where_bg_darker']:.2f} dB (light can "
               f"only be added); smallest residual value {nn['min_residual']:g}.", ""]
        images = _copy_previews(tasks["removal"]["run"], report_dir, scene)
        if images:
            md += [" ".join(f"![{scene} {label}]({path})" for label, path in images), "",
                   "(" + ", ".join(label for label, _ in images) + ")", ""]
    fits = results["fits"]
    md += ["Disentanglement on the held-out views of each fit (background vs its ground truth, foreground "
           "coverage sum max(w_fg, 0) and the fg layer's EXR matte, each at 0.5, IoU vs the exact coverage):", "",
           "| run | bg PSNR | bg PSNR in mask | bg SSIM in mask | fg coverage IoU | fg matte IoU (EXR) | bg phase s |",
           "|---|---|---|---|---|---|---|"]
    for name, f in fits.items():
        h = f["metrics"]["held_out"]
        if "bg_psnr" in h:
            md.append(f"| {name} | {h['bg_psnr']:.2f} | {_f(h['bg_psnr_mask'], 2)} | {_f(h['bg_ssim_mask'], 3)} | "
                      f"{_f(h.get('fg_coverage_iou'), 3)} | {_f(h.get('fg_matte_iou'), 3)} | "
                      f"{_f(f['metrics']['seconds'].get('phase_bg'), 0)} |")
    return md + [""]


def _copy_previews(run, report_dir, scene):
    """Copy one held-out view's previews (full, bg, fg, edits) next to the report."""
    prev = os.path.join(run, "previews")
    if not os.path.isdir(prev):
        return []
    view = sorted(f for f in os.listdir(prev) if f.endswith("_full.png"))
    if not view:
        return []
    stem = view[0][: -len("_full.png")]
    out = []
    for label, path in (("full", f"previews/{stem}_full.png"), ("background", f"previews/{stem}_bg.png"),
                        ("foreground", f"previews/{stem}_fg.png"), ("moved", f"transform/{stem}_composite.png"),
                        ("camouflage", f"camouflage/{stem}_composite.png"),
                        ("light added", f"nonneg/{stem}_composite.png")):
        src = os.path.join(run, path)
        if os.path.isfile(src):
            name = f"{scene}_{label.replace(' ', '_')}.png"
            shutil.copyfile(src, os.path.join(report_dir, name))
            out.append((label, name))
    return out


def _section_header(title, results, command):
    return [f"# {title}", "", f"Run {results['date']} with `{command}` ({results['seconds'] / 60:.1f} min). "
            f"Machine: {results['machine']['cpu']}, {results['machine']['cores']} cores; variant "
            f"`{results['machine']['variant']}`.", ""]


def write_removal(results, report_dir, command, family=None, sheets=None):
    """reports/removal.md: the removal family's lead (``family``, else ``report_dir``/family.json where
    one is, :mod:`mi_voldis.bench.family`; ``sheets``: its contact sheets), then one table per scene
    (strategy rows, OpenCV beside), previews copied beside it. Returns the file's path."""
    from ..fit.config import FitConfig
    from . import family as removal_family
    default = FitConfig().bg_strategy
    os.makedirs(report_dir, exist_ok=True)
    family = family or removal_family.load(report_dir)
    md = _section_header("Removal by background strategy", results, command)
    md += (removal_family.lead(family, sheets) + ["## The scenes the strategies were first chosen on", ""]
           if family else [])
    md += [
          "Each scene is fitted once with the default command (`scripts/train.py DATA --out RUN "
          "--keep-checkpoints`, no setting); from its full field the background is fitted again with each "
          "`bg_strategy` (`python -m mi_voldis.bench.strategies RUN STRATEGY OUT --set ...`, every other "
          "setting as the run's, the background's as today's defaults; `STRATEGY+SETTING` / `STRATEGY-SETTING`: "
          "that boolean setting on / off; `STRATEGY+SETTING=VALUE`: that value). Scores on the held-out views against "
          "the ground-truth background: PSNR inside the masks (dilated by 3% of the diagonal) and outside "
          "them (the full field's outside them beside it), "
          "the object's residue (share of its pixels closer to its own colour than to the true background; "
          "lower is better), view-to-view consistency (each view's result seen from its nearest held-out "
          "neighbour through the background's depth: sampled bilinearly, z-tested in both views, PSNR there "
          "inside the mask), the foreground coverage IoU "
          "(sum max(w_fg, 0) > 0.5 against the exact coverage), and the seconds of the background phase. "
          "Seen / unseen: the in-mask PSNR apart where some training view sees the background unmasked "
          "(`mi_voldis/bench/visible.py`: what the masked loss can reconstruct) and where none does (what "
          "only a prior can fill), the background's point taken at each strategy's own depth (the OpenCV "
          "rows: on the last strategy's pixels). "
          "Telea / Navier-Stokes / FSR (OpenCV contrib's frequency-selective reconstruction): 2D inpainting "
          "of each held-out view itself (they see the photo around the mask); best 2D = the best of the three "
          "per scene.",
          ""] + _removal_targets(results)
    for scene, entry in results["scenes"].items():
        fit = entry["fit"]
        m = fit["metrics"]
        md += [f"## {scene}", "",
               f"Full field: held-out PSNR {m['held_out']['psnr']:.2f} dB, fit {m['seconds']['fit']:.0f} s "
               f"({'reused' if fit['reused'] else 'fitted'} {fit['fitted']} UTC).", "",
               "| strategy | PSNR in mask | seen / unseen | PSNR outside (full field) | residue | consistency | "
               "coverage IoU | bg seconds |", "|---|---|---|---|---|---|---|---|"]
        base = None
        for strategy, row in entry["strategies"].items():
            v = row["methods"]["volume"]
            base = row["methods"]
            md.append(f"| {strategy} | {_f(v['psnr_mask'], 2)} | {_split(v)} | {_f(v['psnr_outside'], 2)} "
                      f"({_f(v.get('full_psnr_outside'), 2)}) | {_f(v['residue'], 2)} | "
                      f"{_f(v['consistency_psnr'], 2)} | {_f(v.get('fg_coverage_iou'), 2)} | {row['seconds']:.0f} |")
        for name in _baselines(base):
            r = base[name]
            md.append(f"| {BASELINES.get(name, name)} | {_f(r['psnr_mask'], 2)} | {_split(r)} | "
                      f"{_f(r['psnr_outside'], 2)} | {_f(r['residue'], 2)} | {_f(r['consistency_psnr'], 2)} | - | - |")
        prior = entry["strategies"].get("lift", {}).get("prior")
        if prior and prior.get("reference_views"):
            shares = ", ".join("-" if x is None else f"{100 * x:.0f}%" for x in prior["seen_elsewhere"])
            md += ["", f"`lift`: reference views {prior['reference_views']}, hole pixels inpainted and lifted "
                       f"{prior['hole_pixels']}, of which another view sees unmasked {shares}; "
                       f"{prior['vertices_emptied']} vertices emptied, {prior['vertices_written']} written."]
        shadow = (entry["strategies"].get(default, {}).get("prior") or {}).get("shadow")
        if shadow:
            md += ["", _shadow_line(shadow)]
        sheet = _removal_sheet(fit["out"], entry["strategies"], os.path.join(report_dir, f"removal_{scene}.png"))
        if sheet:
            md += ["", f"![{scene}]({sheet}) Rows: photo, ground-truth background, {_sheet_baselines()}, then "
                       + ", ".join(f"`{s}`" for s in entry["strategies"]) + "; columns: the first held-out views."]
        md.append("")
    for capture, entry in results.get("captures", {}).items():
        m = entry["fit"]["metrics"]
        md += [f"## {capture} (a capture: no ground truth)", "",
               f"Full field: held-out PSNR {m['held_out']['psnr']:.2f} dB, fit {m['seconds']['fit']:.0f} s. "
               "The earlier default `harmonic`, the default and its variants (`STRATEGY+SETTING` / "
               "`STRATEGY-SETTING`: with that setting on / off; `STRATEGY+SETTING=VALUE`: with that value), with "
               "the view-to-view consistency on every "
               "held-out view (PSNR inside the dilated masks; no ground truth to score against) and the "
               "foreground against the capture's masks (IoU of the coverage sum max(w_fg, 0) and of the EXR "
               "fg layer's matte, each at 0.5).", "",
               "| method | consistency | fg coverage IoU (masks) | fg matte IoU (masks) | bg seconds |",
               "|---|---|---|---|---|"]
        base = None
        for strategy, row in entry["strategies"].items():
            base = row["methods"]
            v = base["volume"]
            md.append(f"| {strategy} | {_f(v['consistency_psnr'], 2)} | {_f(v.get('fg_coverage_iou'), 2)} | "
                      f"{_f(v.get('fg_matte_iou'), 2)} | {row['seconds']:.0f} |")
        for name in _baselines(base):
            md.append(f"| {BASELINES.get(name, name)} | {_f(base[name]['consistency_psnr'], 2)} | - | - | - |")
        sheet = _removal_sheet(entry["fit"]["out"], entry["strategies"],
                               os.path.join(report_dir, f"removal_{capture}.png"), views=None)
        if sheet:
            md += ["", f"![{capture}]({sheet}) Rows: photo, {_sheet_baselines()}, then "
                       + ", ".join(f"`{s}`" for s in entry["strategies"]) + "; columns: every held-out view."]
        md.append("")
    path = os.path.join(report_dir, "removal.md")
    with open(path, "w") as f:
        f.write("\n".join(md) + "\n")
    return path


def _baselines(methods):
    """The 2D methods of a removal result (every method but the volume), in the order they were scored."""
    return [name for name in methods if name != "volume"]


def _shares(shares):
    if not shares:
        return "-"
    return f"{shares['compared']:.2f} ({shares['nearer']:.2f} / {shares['farther']:.2f})"


def _split(row):
    return f"{_f(row.get('psnr_seen'), 2)} / {_f(row.get('psnr_unseen'), 2)}"


def _shadow_line(shadow):
    """The object's shadow as the default's search found it (:mod:`mi_voldis.fit.shadow`), in one line."""
    light = ", ".join(f"{x:.2f}" for x in shadow["light"])
    verdict = "kept: its shadow joins the effect masks" if shadow["kept"] else "not kept"
    return (f"Shadow search of the default: best light ({light}), edge contrast {shadow['contrast']:.2f}, views "
            f"agreeing {shadow['views_agree']:.2f}, shading {shadow['shading']:.2f}; {verdict}.")


def _removal_targets(results):
    """The default strategy against the best 2D method per scene: in-mask PSNR (target: 2D + 2 dB),
    consistency (2D + 3 dB), PSNR outside against the full field's (within 0.5 dB), coverage IoU (0.9)."""
    from ..fit.config import FitConfig
    default = FitConfig().bg_strategy
    md = [f"## Default strategy (`{default}`) against the best 2D method", "",
          "| scene | PSNR in mask | best 2D | margin | margin over Telea / NS (target +2) | consistency | best 2D | "
          "margin (target +3) | ground truth's consistency | share compared (nearer / farther) | outside - full field "
          "(target >= -0.5) | coverage IoU (target 0.9) | residue |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    margins = []
    for scene, entry in results["scenes"].items():
        row = entry["strategies"].get(default)
        if row is None:
            continue
        m = row["methods"]
        v = m["volume"]
        best = max(m[name]["psnr_mask"] for name in _baselines(m))
        best_c = max(m[name]["consistency_psnr"] for name in _baselines(m))
        classic = max(m[name]["psnr_mask"] for name in ("telea", "ns") if name in m)
        margins.append(v["psnr_mask"] - best)
        md.append(f"| {scene} | {_f(v['psnr_mask'], 2)} | {_f(best, 2)} | {v['psnr_mask'] - best:+.2f} | "
                  f"{v['psnr_mask'] - classic:+.2f} | {_f(v['consistency_psnr'], 2)} | {_f(best_c, 2)} | "
                  f"{v['consistency_psnr'] - best_c:+.2f} | {_f(v.get('truth_consistency_psnr'), 2)} | "
                  f"{_shares(v.get('consistency_shares'))} | {v['psnr_outside'] - v['full_psnr_outside']:+.2f} | "
                  f"{_f(v.get('fg_coverage_iou'), 2)} | "
                  f"{_f(v['residue'], 2)} |")
    if margins:
        md += ["", f"Mean in-mask margin over the best 2D method: {sum(margins) / len(margins):+.2f} dB "
                   f"(from {min(margins):+.2f} to {max(margins):+.2f}). Ground truth's consistency: the "
                   "ground-truth background scored by the same metric (warped with the default's depth): "
                   "what a correct answer gets through the volume's geometry, the reference for the consistency "
                   "column. Share compared: the part of the dilated masks the consistency scores; nearer / "
                   "farther: the parts it leaves out because the other view's depth is nearer (an occluder) "
                   "or farther (the views' depths disagree) than the point by more than 3%.", ""]
    return md


SHEET_WIDTH = 1600  # pixels across a removal sheet at most


SHEET_BASELINES = ("telea", "fsr")  # the 2D inpaintings a removal contact sheet shows, where installed


def _sheet_baselines():
    return ", ".join(BASELINES[name] for name in SHEET_BASELINES if name in available_baselines())


def _removal_sheet(run, strategies, path, views=3):
    """One PNG: for the first ``views`` held-out views (None: all; columns), the photo, the ground-truth
    background (when the dataset has one), OpenCV's Telea and contrib FSR inpaintings and each
    strategy's background (rows). Returns its file name, or None."""
    import json

    import imageio.v3 as iio

    from ..data import load_dataset
    from ..inpaint2d import inpainter
    from ..io.images import contact_sheet, display_to_uint8, write_png
    from ..metrics import dilate, score_dilation
    if not os.path.isfile(os.path.join(run, "config.json")):  # the run is gone: its sheet, if written, stays
        return os.path.basename(path) if os.path.isfile(path) else None
    with open(os.path.join(run, "config.json")) as f:
        config = json.load(f)
    record = config["dataset"]
    ds = load_dataset(record["path"], record["format"], record["holdout"])
    tests = [v for v in ds.test if all(os.path.isfile(os.path.join(r["out"], f"view{v:03d}_bg.png"))
                                       for r in strategies.values())][:views]
    if not tests or ds.masks is None:
        return None
    dil = score_dilation(ds.size)
    rows = [[display_to_uint8(ds.images[v]) for v in tests]]
    if ds.backgrounds is not None:
        rows.append([display_to_uint8(ds.backgrounds[v]) for v in tests])
    rows += [[display_to_uint8(inpainter(name)(ds.images[v], dilate(ds.masks[v], dil))) for v in tests]
             for name in SHEET_BASELINES if name in available_baselines()]
    rows += [[iio.imread(os.path.join(r["out"], f"view{v:03d}_bg.png"))[..., :3] for v in tests]
             for r in strategies.values()]
    images = [im for row in rows for im in row]
    factor = -(-len(tests) * ds.size[1] // SHEET_WIDTH)  # whole views, at most SHEET_WIDTH pixels across
    if factor > 1:
        import cv2
        images = [cv2.resize(im, (im.shape[1] // factor, im.shape[0] // factor), interpolation=cv2.INTER_AREA)
                  for im in images]
    write_png(path, contact_sheet(images, columns=len(tests)))
    return os.path.basename(path)


def write_masks(results, report_dir, command):
    """reports/masks.md: masks from two views against exact coverage, and removal with them beside
    removal with every true mask; a sheet per scene. Returns the file's path."""
    os.makedirs(report_dir, exist_ok=True)
    md = _section_header("Object masks from two views", results, command) + [
          "Per scene, from the removal section's default fit (its full field): two training views get their "
          "true masks (the first training view and the one that sees the rig's common target from the "
          "direction closest to 90 degrees from the first's: `mi_voldis.bench.masks.given_views`), "
          "`scripts/make_masks.py` makes masks for every view "
          "(`python -m mi_voldis.bench.masks RUN OUT`), scored against the exact visible coverage > 0.5 on "
          "every other view; then the background is fitted again from the same full field with those masks "
          "(default `bg_strategy`) and scored like the removal with every true mask (in-mask PSNR on the "
          "held-out views, inside the true masks dilated by 3% of the diagonal).", "",
          "| scene | given views | mask IoU mean | mask IoU min | removal in-mask PSNR, made masks | "
          "with true masks | difference |", "|---|---|---|---|---|---|---|"]
    for scene, row in results["scenes"].items():
        made = row["removal"]["methods"]["volume"]["psnr_mask"]
        true = row["removal_true_masks"]["methods"]["volume"]["psnr_mask"]
        diff = None if made is None or true is None else made - true
        md.append(f"| {scene} | {', '.join(row['given'])} | {_f(row['iou_mean'], 3)} | {_f(row['iou_min'], 3)} | "
                  f"{_f(made, 2)} | {_f(true, 2)} | {_f(diff, 2)} |")
    return _write_with_sheets(md, results, report_dir, "masks", _masks_sheet,
                              "rows photo, exact coverage > 0.5, made mask; columns: the three views of lowest IoU.")


def write_effects(results, report_dir, command):
    """reports/effects.md: removal with and without the object's shadow as effect masks, beside OpenCV's
    inpainting given the same masks; a sheet per scene. Returns the file's path."""
    os.makedirs(report_dir, exist_ok=True)
    md = _section_header("Removal with the object's shadow as an input", results, command) + [
          "Per scene, from the removal section's default fit (its full field): the pixels outside the object's "
          "mask where the photo differs from the ground-truth background (the object's shadow, its reflection: "
          "`mi_voldis.bench.effects.effect_masks`) become the dataset's effect masks (`effect_mask_path`), and "
          "the background is fitted again with the default `bg_strategy` without them and with them "
          "(`python -m mi_voldis.bench.effects RUN OUT`); scored as the removal section scores, against the "
          "ground-truth background inside the object's masks dilated by 3% of the diagonal. The 2D methods "
          "inpaint each held-out view itself: in its dilated mask, and in that and its effect mask (the same "
          "input as the volume's). Effect area: mean over training views, as a share of the object's.", "",
          "| scene | effect area | in mask, without | with | Telea / NS, mask | Telea / NS, mask + effect | "
          "with: margin over the best Telea / NS | outside, without / with (full field) | coverage IoU, "
          "without / with | matte IoU, without / with | seconds (with) |",
          "|---|---|---|---|---|---|---|---|---|---|---|"]
    for scene, row in results["scenes"].items():
        a, b = row["without"]["methods"], row["with"]["methods"]
        va, vb, flat = a["volume"], b["volume"], row["effects_2d"]
        best = max(x for x in (flat.get("telea"), flat.get("ns"), a["telea"]["psnr_mask"], a["ns"]["psnr_mask"])
                   if x is not None)
        md.append(f"| {scene} | {row['effect_share']:.2f} | {_f(va['psnr_mask'], 2)} | {_f(vb['psnr_mask'], 2)} | "
                  f"{_f(a['telea']['psnr_mask'], 2)} / {_f(a['ns']['psnr_mask'], 2)} | "
                  f"{_f(flat.get('telea'), 2)} / {_f(flat.get('ns'), 2)} | {vb['psnr_mask'] - best:+.2f} | "
                  f"{_f(va['psnr_outside'], 2)} / {_f(vb['psnr_outside'], 2)} ({_f(va.get('full_psnr_outside'), 2)}) | "
                  f"{_f(va.get('fg_coverage_iou'), 2)} / {_f(vb.get('fg_coverage_iou'), 2)} | "
                  f"{_f(va.get('fg_matte_iou'), 2)} / {_f(vb.get('fg_matte_iou'), 2)} | {row['with']['seconds']:.0f} |")
    return _write_with_sheets(md, results, report_dir, "effects", _effects_sheet,
                              "rows photo with its effect mask in red, ground-truth background, the background "
                              "without effect masks, with them; columns: the first held-out views.")


def _write_with_sheets(md, results, report_dir, name, sheet, caption):
    """Write ``md`` and, per scene, the sheet ``sheet(row, path)`` makes (``<name>_<scene>.png``) with its
    ``caption`` to ``<name>.md`` in ``report_dir``. Returns the file's path."""
    md = md + [""]
    for scene, row in results["scenes"].items():
        made = sheet(row, os.path.join(report_dir, f"{name}_{scene}.png"))
        if made:
            md += [f"![{scene}]({made}) {scene}: {caption}", ""]
    path = os.path.join(report_dir, f"{name}.md")
    with open(path, "w") as f:
        f.write("\n".join(md) + "\n")
    return path


def _effects_sheet(row, path, views=3):
    """One PNG: for the first ``views`` held-out views (columns), the photo with its effect mask in red,
    the ground-truth background, and the background without and with effect masks (rows). Returns its
    file name, or None."""
    import imageio.v3 as iio
    import numpy as np

    from ..data import load_dataset
    from ..io.images import contact_sheet, display_to_uint8, write_png
    data = os.path.join(row["out"], "data")
    if not os.path.isdir(data):
        return None
    ds = load_dataset(data, "transforms")
    tests = [v for v in ds.test if all(os.path.isfile(os.path.join(row["out"], key, f"view{v:03d}_bg.png"))
                                       for key in ("without", "with"))][:views]
    if not tests:
        return None
    marked = []
    for v in tests:
        image = np.clip(ds.images[v], 0, 1)
        marked.append(np.where(ds.effects[v][..., None], 0.5 * image + [0.5, 0.0, 0.0], image))
    rows = [[display_to_uint8(m) for m in marked], [display_to_uint8(ds.backgrounds[v]) for v in tests]]
    rows += [[iio.imread(os.path.join(row["out"], key, f"view{v:03d}_bg.png"))[..., :3] for v in tests]
             for key in ("without", "with")]
    write_png(path, contact_sheet([im for r in rows for im in r], columns=len(tests)))
    return os.path.basename(path)


def _masks_sheet(row, path, views=3):
    import numpy as np

    from ..data import load_dataset
    from ..io.images import contact_sheet, display_to_uint8, write_png
    truth_ds = load_dataset(row["data"])
    made_ds = load_dataset(os.path.join(row["out"], "data"))
    worst = sorted((v for v in row["per_view"] if v not in row["given"]), key=lambda n: row["per_view"][n])[:views]
    idx = [truth_ds.names.index(n) for n in worst]
    if not idx:
        return None
    truth = truth_ds.coverage > 0.5 if truth_ds.coverage is not None else truth_ds.masks
    grey = lambda m: np.repeat(np.where(m, 255, 0).astype(np.uint8)[..., None], 3, axis=2)  # noqa: E731
    tiles = [display_to_uint8(truth_ds.images[v]) for v in idx] + [grey(truth[v]) for v in idx] + \
        [grey(made_ds.masks[v]) for v in idx]
    write_png(path, contact_sheet(tiles, columns=len(idx)))
    return os.path.basename(path)
