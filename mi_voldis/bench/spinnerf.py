"""Removal scored with SPIn-NeRF's protocol on random scenes in SPIn-NeRF's layout:
``scripts/bench.py --spinnerf [--scenes family10,...] [--lpips-weights DIR]``.

The protocol, so that the numbers sit beside the peers' tables (SPIn-NeRF, GScream):

* data: family scene K (:mod:`mi_voldis.synth.family`, the check half by default) rendered by
  ``make_dataset.py --family K --layout spinnerf``: :data:`~mi_voldis.synth.make.SPINNERF_TEST_SHARE` of the
  rig's views, spread evenly over it, photographed without the object (the test views; ``images_4/test_label``
  marks where it stood), the others with it and its masks (``images_4/label``), poses in ``poses_bounds.npy``;
* fit: the default command (``scripts/train.py DATA --out RUN``, no setting) on the training views;
* ours: the run's background layer rendered at each test pose (pixel centres, display-encoded, clipped to
  [0, 1]) against the object-free photo;
* the 2D baselines as the peers run theirs: the full field's render at each test pose (the object still in
  it) inpainted inside the same dilated test mask by OpenCV Telea and Navier-Stokes, against the same photo;
* metrics (:func:`mi_voldis.evaluate.score_view`): PSNR and SSIM over the whole image, inside the test mask
  dilated by ``ceil(DILATION * diagonal)`` pixels, and over that dilated mask's bounding box (both images
  cropped); LPIPS (AlexNet v0.1, :mod:`mi_voldis.lpips`, local weights only) on the whole image and the box
  when both are at least :data:`~mi_voldis.evaluate.LPIPS_MIN` pixels a side. Means over a scene's test views,
  then over scenes; the worst scene is the one where our in-mask PSNR is lowest.

Results in ``report_dir``/spinnerf.json, the report in spinnerf.md (:func:`write_spinnerf`).
"""
import os
import time

import numpy as np

from ..synth import family
from .run import fit, make_data, new_results, save_results, section_scenes

DILATION = 0.01  # fraction of the image diagonal: scripts/evaluate.py's --dilate default, used on the capture in #46
BASELINES = {"telea": "OpenCV Telea", "ns": "OpenCV Navier-Stokes"}
METHODS = {"ours": "ours (background layer)", **BASELINES}
# the peers' published means (their tables, as quoted in issue #46): whole-image and in-mask PSNR in dB
PEERS = {"SPIn-NeRF": {"psnr_image": 20.18, "psnr_mask": 15.80}, "GScream": {"psnr_image": 20.49, "psnr_mask": 15.84}}
PEERS_NOTE = ("theirs, not ours: measured on SPIn-NeRF's ten real captures (not these scenes), with learned 2D "
              "inpainters and each paper's own evaluation code, averaged over the ten")
COLUMNS = [("psnr_image", "PSNR whole", 2), ("psnr_mask", "PSNR mask", 2), ("psnr_bbox", "PSNR bbox", 2),
           ("ssim_image", "SSIM whole", 3), ("ssim_mask", "SSIM mask", 3), ("ssim_bbox", "SSIM bbox", 3),
           ("lpips_image", "LPIPS whole", 3), ("lpips_bbox", "LPIPS bbox", 3)]


def view_means(rows):
    """{metric: mean over the views that have it, or None where none has it} of per-view score rows."""
    keys = next(iter(rows.values())).keys() if rows else ()
    defined = {k: [r[k] for r in rows.values() if r.get(k) is not None] for k in keys}
    return {k: float(np.mean(v)) if v else None for k, v in defined.items()}


def score_baselines(renders, truths, masks, dil, perceptual=None):
    """Each of :data:`BASELINES` on every view: ``renders[name]`` (H, W, 3) in [0, 1], the full field's render
    at a test pose, inpainted inside ``masks[name]`` dilated by ``dil`` pixels and scored against
    ``truths[name]`` by :func:`~mi_voldis.evaluate.score_view` (which dilates the mask the same way).
    Returns {method: {"views", "mean", "per_view"}}."""
    from ..evaluate import score_view
    from ..inpaint2d import inpainter
    from ..metrics import dilate
    out = {}
    for method in BASELINES:
        fill = inpainter(method)
        rows = {name: score_view(fill(renders[name], dilate(masks[name], dil)), truths[name], masks[name], dil,
                                 perceptual) for name in renders}
        out[method] = {"views": len(rows), "mean": view_means(rows), "per_view": rows}
    return out


def score_run(run_dir, perceptual=None, dilation=DILATION):
    """Our background layer and the 2D baselines on the test views of a fitted run's own dataset (the
    module docstring's protocol): {"views", "train_views", "dilation_px", "size" ([width, height]),
    "methods": {method: {"views", "mean", "per_view"}}}."""
    from ..evaluate import evaluate_removal, scored_views
    from ..metrics import diagonal_pixels
    from ..render.views import render_camera
    from ..tasks.base import FittedRun
    fitted = FittedRun(run_dir)
    ds, integrator = fitted.dataset, fitted.integrator()
    views = scored_views(ds)
    if not views:
        raise ValueError(f"{ds.root}: no test view has a ground-truth background and an object mask "
                         "(SPIn-NeRF's images_K/test_label/)")
    dil = diagonal_pixels(dilation, ds.size)  # as evaluate_removal turns the fraction into pixels
    ours = evaluate_removal(integrator, ds, dilation, perceptual)
    full = {ds.names[v]: np.clip(render_camera(integrator, ds.cameras[v], ("full",))["full"][0], 0, 1)
            for v in views}
    truths = {ds.names[v]: ds.backgrounds[v] for v in views}
    masks = {ds.names[v]: ds.masks[v] for v in views}
    methods = {"ours": {k: ours[k] for k in ("views", "mean", "per_view")},
               **score_baselines(full, truths, masks, dil, perceptual)}
    height, width = ds.size
    return {"views": len(views), "train_views": len(ds.train), "dilation_px": dil, "size": [width, height],
            "methods": methods}


def lpips_note(lpips_weights):
    """Why a report has no (or only some) LPIPS: no weights given, or views too small for the box."""
    if not lpips_weights:
        return ("no LPIPS: no --lpips-weights folder given (nothing is downloaded; mi_voldis/lpips.py names the two "
                "files it needs)")
    from ..evaluate import LPIPS_MIN
    return (f"LPIPS from {lpips_weights} (AlexNet v0.1); a bounding box under {LPIPS_MIN} pixels a side has none "
            "(AlexNet's strides and pooling need them)")


def run_spinnerf(work, report_dir, scenes=None, lpips_weights=None):
    """Render, fit and score each chosen scene (``scenes``: family names; default the check half): datasets in
    ``work``/data/<scene>_spinnerf, runs in ``work``/runs/<scene>_spinnerf_0 (both reused when finished);
    results in ``report_dir``/spinnerf.json."""
    chosen = section_scenes("spinnerf", scenes)
    perceptual = None
    if lpips_weights:  # before any fit: a bad weights folder stops the section at once
        from ..lpips import load_lpips
        perceptual = load_lpips(lpips_weights)
    results = new_results()
    results.update(chosen=chosen, dilation=DILATION,
                   lpips={"weights": os.path.abspath(lpips_weights) if lpips_weights else None,
                          "note": lpips_note(lpips_weights)})
    logs = os.path.join(work, "logs")
    os.makedirs(logs, exist_ok=True)
    t0 = time.perf_counter()
    for scene in chosen:
        data = make_data(scene, os.path.join(work, "data", f"{scene}_spinnerf"), logs, False, layout="spinnerf")
        run = fit(data, os.path.join(work, "runs", f"{scene}_spinnerf_0"), [], logs)
        k = family.index(scene)
        seed, kind = family.scene(k)
        results["scenes"][scene] = {"fit": run, "half": family.half(k), "seed": seed, "kind": kind,
                                    **score_run(run["out"], perceptual)}
    results["seconds"] = time.perf_counter() - t0
    return save_results(results, report_dir, "spinnerf.json")


def section(lpips_weights=None):
    """The (measure, write) pair ``scripts/bench.py --spinnerf`` runs: the weights folder rides along to the
    measure, and into the command the report states."""
    flag = f" --lpips-weights {lpips_weights}" if lpips_weights else ""
    return (lambda work, report_dir, scenes: run_spinnerf(work, report_dir, scenes, lpips_weights),
            lambda results, report_dir, command: write_spinnerf(results, report_dir, command + flag))


# ------------------------------------------------------------------------------------ the report
def summary(results):
    """{'mean': {method: {metric: mean over scenes}}, 'worst': scene with our lowest in-mask PSNR, 'n'}, or
    None without scenes."""
    scenes = results["scenes"]
    if not scenes:
        return None
    mean = {}
    for method in METHODS:
        rows = {s: e["methods"][method]["mean"] for s, e in scenes.items() if method in e["methods"]}
        mean[method] = view_means(rows)  # the same rule one level up: scenes instead of views
    worst = min(scenes, key=lambda s: scenes[s]["methods"]["ours"]["mean"]["psnr_mask"])
    return {"mean": mean, "worst": worst, "n": len(scenes)}


def _f(x, digits):
    return "-" if x is None or x != x else f"{x:.{digits}f}"


def _row(label, method, numbers):
    return f"| {label} | {method} | " + " | ".join(_f(numbers.get(k), d) for k, _, d in COLUMNS) + " |"


def margin(entry):
    """Our in-mask PSNR minus the better 2D baseline's on one scene."""
    m = entry["methods"]
    return m["ours"]["mean"]["psnr_mask"] - max(m[b]["mean"]["psnr_mask"] for b in BASELINES if b in m)


def protocol(results):
    """The paragraph that states the protocol precisely."""
    from ..synth.make import SPINNERF_TEST_SHARE
    sizes = {tuple(e["size"]): e["dilation_px"] for e in results["scenes"].values()}
    px = ", ".join(f"{d} px at {w}x{h}" for (w, h), d in sizes.items())
    return (f"Protocol. Each scene is family scene K rendered by `python scripts/make_dataset.py --family K --layout "
            f"spinnerf` (Mitsuba's path tracer): {SPINNERF_TEST_SHARE:.0%} of the rig's views, spread evenly over it, "
            "are photographed without the object (the test views; `images_4/test_label/` marks where it stood), the "
            "others with it and its masks (`images_4/label/`), poses in `poses_bounds.npy` for all. It is fitted "
            "with the default command (`python scripts/train.py DATA --out RUN`, no setting) on the training views "
            "only. Ours: the run's background layer rendered at each test pose through pixel centres, "
            "display-encoded and clipped to [0, 1]. Telea / NS: the full field's render at the same pose (the "
            "object still in it) inpainted by OpenCV (radius 5, 8-bit) inside the test mask dilated as below. "
            "Each is compared with the object-free test photo: PSNR and SSIM over the whole image, inside the "
            f"test mask dilated by ceil({DILATION:g} x the image diagonal) pixels ({px or 'no scene'}), and over "
            "the bounding box of that dilated mask (both images cropped to it); LPIPS (AlexNet v0.1) on the whole "
            "image and on the box. Means over a scene's test views, then over scenes; the worst scene is the one "
            "where our in-mask PSNR is lowest.")


def write_spinnerf(results, report_dir, command):
    """``report_dir``/spinnerf.md from :func:`run_spinnerf`'s results; returns its path."""
    head = "| scene | method | " + " | ".join(name for _, name, _ in COLUMNS) + " |"
    rule = "|---|---|" + "---|" * len(COLUMNS)
    seconds = results.get("seconds")
    md = ["# Removal under SPIn-NeRF's protocol, on random scenes in its layout", "",
          f"Run {results['date']} (`{command}`" + (f", {seconds / 60:.1f} min" if seconds is not None else "") +
          f"; {results['machine']['cpu']}, {results['machine']['cores']} cores). Scenes: "
          f"{', '.join(results['scenes']) or 'none'}. {results['lpips']['note']}.", ""]
    s = summary(results)
    if s:
        worst = results["scenes"][s["worst"]]
        ours = worst["methods"]["ours"]["mean"]
        md += [f"Worst scene: {s['worst']} ({worst['kind']} rig), ours {ours['psnr_mask']:.2f} dB in the mask, "
               f"{margin(worst):+.2f} dB over the better of Telea / NS; mean over {s['n']} scene{'s' * (s['n'] != 1)}: "
               f"ours {s['mean']['ours']['psnr_image']:.2f} dB whole / {s['mean']['ours']['psnr_mask']:.2f} dB in the "
               "mask.", ""]
        md += ["## Mean over scenes, worst scene, and the peers' published numbers", "", head, rule]
        md += [_row(f"mean of {s['n']}", METHODS[m], s["mean"][m]) for m in METHODS]
        md += [_row(f"worst: {s['worst']}", METHODS[m], worst["methods"][m]["mean"]) for m in METHODS]
        md += [_row(f"{peer} (theirs)", "published mean", numbers) for peer, numbers in PEERS.items()]
        md += ["", f"The peers' rows are {PEERS_NOTE}: they compare in kind, not scene by scene.", ""]
        md += ["## Per scene", "", head, rule]
        for scene, entry in results["scenes"].items():
            md += [_row(f"{scene} ({entry['kind']}, {entry['views']} test views)", METHODS[m],
                        entry["methods"][m]["mean"]) for m in METHODS if m in entry["methods"]]
        md.append("")
    md += [protocol(results), ""]
    os.makedirs(report_dir, exist_ok=True)
    path = os.path.join(report_dir, "spinnerf.md")
    with open(path, "w") as f:
        f.write("\n".join(md) + "\n")
    return path
