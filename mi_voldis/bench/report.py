"""reports/bench.md and its plots, from the results of :func:`mi_voldis.bench.run.run_all`."""
import os
import shutil

from . import rays
from .machine import BYTES_FORWARD, BYTES_TRAIN
from .run import msps_bound, time_to_within


def _f(x, digits=1):
    return "-" if x is None else f"{x:.{digits}f}"


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
    md += _memory(results)
    with open(os.path.join(report_dir, "bench.md"), "w") as f:
        f.write("\n".join(md) + "\n")


def _throughput(results):
    bw = results["bandwidth"]
    fwd_bound, train_bound = msps_bound(bw["drjit_gbs"], BYTES_FORWARD), msps_bound(bw["drjit_gbs"], BYTES_TRAIN)
    tile = rays.TILE
    md = ["## 1. Ray-marcher throughput (density + RGB grid)", "",
          f"Memory bandwidth (large copy): {bw['drjit_gbs']:.1f} GB/s with Dr.Jit on all cores, "
          f"{bw['numpy_gbs']:.1f} GB/s with NumPy on one. A sample touches {BYTES_FORWARD} B forward "
          f"(8 corners x 4 floats) and {BYTES_TRAIN} B in training (lookup, gradient read-modify-write, and the "
          f"16-byte record of the lookup written and read back): bounds of {fwd_bound:.0f} and {train_bound:.0f} "
          "Msps. These count bytes as if streamed; the lookups and scatters are scattered 16-byte accesses.", "",
          "Rays (`mi_voldis/bench/rays.py`): *random* rays, each independent of its neighbours, and *tiles*, "
          f"coherent rays: {tile} x {tile} pixel tiles of random views, whose rays march side by side through the "
          "same cells (as in a rendered view, or fitting with `batch_tile=4`; section 2 shows what that does to "
          "fitting). The training step is fitting's (Adam on the packed grids). PyTorch (the same model with "
          "`grid_sample`, `mi_voldis/bench/torch_reference.py`) runs on the same rays in the rows with 128 samples "
          "per ray (its steps take seconds; all rows would not fit the hour).", "",
          "| grid | samples/ray | batch | rays | voldis fwd Msps | voldis train Msps | % of bound | torch fwd Msps | "
          "torch train Msps | train ratio |", "|---|---|---|---|---|---|---|---|---|---|"]
    for row in results["throughput"]:
        v, t = row["voldis"], row.get("torch")
        ratio = v["train"]["msps"] / t["train"]["msps"] if t else None
        md.append(f"| {row['resolution']}^3 | {row['samples']} | {row['batch']} | {row.get('rays', 'random')} | "
                  f"{v['forward']['msps']:.1f} | "
                  f"{v['train']['msps']:.1f} | {100 * v['train']['msps'] / train_bound:.0f}% | "
                  f"{_f(t and t['forward']['msps'])} | {_f(t and t['train']['msps'], 2)} | {_f(ratio)}x |")
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
    md = ["## 2. Speed against error (fitting)", "", "![speed vs error](speed_vs_error.png)", "",
          "| run | held-out PSNR | SSIM | fit s | to within 0.5 dB of best, s | evaluated samples/ray | "
          "SH degree | grid |", "|---|---|---|---|---|---|---|---|"]
    for name, f in results["fits"].items():
        m = f["metrics"]
        best = max((p for _, p in f["curve"]), default=None)
        within = time_to_within(f["curve"], best) if best else None
        md.append(f"| {name} | {m['held_out']['psnr']:.2f} | {m['held_out']['ssim']:.3f} | "
                  f"{m['seconds']['fit']:.0f} | {_f(within, 0)} | {_f(m['evaluated_samples_per_ray'], 0)} | "
                  f"{m['sh_degree']} | {'x'.join(map(str, m['grid']['full']))} |")
    md += ["", "Commands:", ""] + [f"- {name}: `{f['command']}`" for name, f in results["fits"].items()]
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
                   "PSNR whole | view consistency PSNR |", "|---|---|---|---|---|"]
            labels = {"volume": "background volume (ours)", "telea": "OpenCV Telea", "ns": "OpenCV Navier-Stokes"}
            for name, r in removal["methods"].items():
                label = labels[name]
                md.append(f"| {label} | {_f(r['psnr_mask'], 2)} | {_f(r['ssim_mask'], 3)} | {_f(r['psnr'], 2)} | "
                          f"{_f(r['consistency_psnr'], 2)} |")
            md.append("")
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
           "coverage IoU at 0.5 vs the exact coverage):", "",
           "| run | bg PSNR | bg PSNR in mask | bg SSIM in mask | fg alpha IoU | fg coverage IoU | bg phase s |",
           "|---|---|---|---|---|---|---|"]
    for name, f in fits.items():
        h = f["metrics"]["held_out"]
        if "bg_psnr" in h:
            md.append(f"| {name} | {h['bg_psnr']:.2f} | {h['bg_psnr_mask']:.2f} | {h['bg_ssim_mask']:.3f} | "
                      f"{h['fg_iou']:.3f} | {h['fg_coverage_iou']:.3f} | "
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


def _memory(results):
    md = ["## 5. Peak memory of fitting", "", "Peak resident memory of each fitting process (`VmHWM`, "
          "recorded by the process itself in its metrics.json).", "",
          "| run | grid | peak RSS (MiB) |", "|---|---|---|"]
    for name, f in results["fits"].items():
        md.append(f"| {name} | {'x'.join(map(str, f['metrics']['grid']['full']))} | {_f(f['rss_mib'], 0)} |")
    return md + [""]
