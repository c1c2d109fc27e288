"""Removal by background strategy, from one fitted full field (the benchmark's removal section).

    python -m mi_voldis.bench.strategies RUN STRATEGY OUT [MASKED_DATASET] [--set KEY=VALUE ...] [--refit]

RUN: a finished fit kept with ``--keep-checkpoints``; its final state's full field is reused, the
background is fitted again with ``bg_strategy=STRATEGY`` (where RUN's settings are those very ones, its own
background is scored instead: the same computation, unless ``--refit``, for a background phase whose
code changed since RUN was fitted; the benchmark always refits) (the background phase's other settings,
:data:`BACKGROUND_SETTINGS`, as today's defaults, whatever RUN recorded; every other one as RUN's
config.json), and
OUT receives ``metrics.json``, the background of each held-out view as PNG and, where the foreground is
scored, its coverage against the truth (``viewNNN_coverage.png``: :func:`coverage_errors`). Rendered as the run's
scene.xml renders (its occupancy grid: :func:`~mi_voldis.fit.fields.scene_integrator`) and scored on the
held-out views against the ground-truth background (in-mask = masks dilated by
:data:`~mi_voldis.metrics.SCORE_DILATION`, whatever the fit's ``hull_dilation``): PSNR inside
the masks (and there, apart, where some training view sees the background unmasked and where none
does: :mod:`mi_voldis.bench.visible`) and outside them (beside the full field's outside them), the
object's residue, the foreground's IoU (its coverage and its EXR matte; on a capture without ground
truth against its masks), the view-to-view consistency and where the background stands behind
the object (:func:`~mi_voldis.bench.visible.mask_surfaces`); the 2D inpainters of
:data:`~mi_voldis.inpaint2d.BASELINES` on each held-out view itself (they see the photo around the
mask) beside them. MASKED_DATASET: fit the
background with that copy of RUN's dataset (other object masks, e.g. from scripts/make_masks.py);
scores still use RUN's dataset and its ground-truth masks (where RUN's dataset has no masks, a capture
such as garden with masks made from a box, they use MASKED_DATASET's). ``--set``: settings over RUN's (as
``scripts/train.py --set``).
"""
import json
import os
import sys
import time

import numpy as np

PREVIEWS = 4  # held-out views previewed when the dataset has neither ground truth nor masks to score

# the background strategies' own settings (bg_strategy first): a refit takes today's defaults for them, so
# that a run fitted under older defaults is scored with the strategy the default command runs now
BACKGROUND_SETTINGS = ("bg_strategy", "prior_weight", "prior_rays", "prior_views", "prior_inpainter", "object_alpha",
                       "object_front", "object_behind_fill", "object_behind_layers",
                       "hole_carve", "hole_carve_margin", "hole_carve_behind",
                       "keep_seen", "keep_seen_gap", "seen_surface_tol", "hull_color_fill", "hull_fill_vertical",
                       "hull_occluders", "shadow_contrast", "fringe_contrast", "fringe_width", "fringe_unseen",
                       "bg_lr_density", "bg_lr_color", "bg_tv_density", "bg_tv_color")


def helper_arguments(argv, name):
    """RUN and OUT of a bench helper, ``python -m mi_voldis.bench.NAME RUN OUT``: RUN must hold a fit's
    config.json, and OUT is claimed for ``bench_NAME`` (new, empty or its own: :func:`~mi_voldis.io.run_folder.
    claim`); anything else stops with one line."""
    from ..io.run_folder import claim
    args = list(argv or sys.argv[1:])
    if len(args) < 2:
        raise SystemExit(f"usage: python -m mi_voldis.bench.{name} RUN OUT")
    run, out = args[:2]
    if not os.path.isfile(os.path.join(run, "config.json")):
        raise SystemExit(f"error: {run}: no config.json (not a fitted run)")
    try:
        claim(out, f"bench_{name}")
    except ValueError as e:
        raise SystemExit(f"error: {e}") from None
    return run, out


def out_problem(out, run, dataset):
    """Why OUT may not receive a refit's files (None if it may): it is RUN or the dataset, or inside one
    of them, or it holds a metrics.json no refit wrote (a run's, a user's); a refit's own is replaced."""
    real = os.path.realpath(out)
    for name, folder in (("the run", run), ("its dataset", dataset)):
        base = os.path.realpath(folder)
        if real == base or real.startswith(base + os.sep):
            return f"is {name} {folder} or inside it: give a new folder"
    metrics = os.path.join(out, "metrics.json")
    if os.path.exists(metrics):
        try:
            with open(metrics) as f:
                ours = "strategy" in json.load(f)
        except (OSError, ValueError):
            ours = False
        if not ours:
            return "holds a metrics.json that no background refit wrote: give a new folder"
    return None


def refit_config(run, strategy, sets=()):
    """The settings of a background refit from ``run``: its config.json, the background phase's settings
    as today's defaults with ``bg_strategy=strategy``, then ``sets`` ("name=value")."""
    from ..fit.config import FitConfig
    today = FitConfig()
    background = {key: getattr(today, key) for key in BACKGROUND_SETTINGS[1:]}
    return FitConfig.from_sources(os.path.join(run, "config.json"), list(sets), bg_strategy=strategy, **background)


def same_settings(run, cfg):
    """``run``'s config.json holds exactly the settings ``cfg`` resolves to on this backend (what was
    fitted on what, :data:`~mi_voldis.settings.RECORD_KEYS`, aside; settings added since it was fitted
    at the values it was fitted with: :meth:`~mi_voldis.settings.Settings.recorded`)."""
    from ..fit.config import FitConfig
    from ..fit.schedule import backend
    with open(os.path.join(run, "config.json")) as f:
        recorded = FitConfig.recorded(json.load(f))
    return recorded == cfg.for_backend(backend()).to_dict()


def evaluate(ds, integrator, hull_min_views=0.9):
    """Per-method rows (the volume's background, then each 2D baseline) and the volume's held-out renders."""
    from ..compositing import composite_channels
    from ..fit.report import background_haze, mean_defined
    from ..inpaint2d import available_baselines, inpainter
    from ..metrics import dilate, iou, object_residue, psnr, score_dilation
    from ..render.views import layer_channels, render_camera
    from ..tasks.removal import consistency, consistency_shares
    from .visible import mask_surfaces, seen_pixels, training_surfaces
    dil = score_dilation(ds.size)
    scored = [v for v in ds.test if ds.backgrounds is not None and np.isfinite(ds.backgrounds[v]).all()]
    # without ground truth: the consistency alone, on every held-out view (none without masks either)
    tests = scored or (list(ds.test) if ds.masks is not None else [])
    renders = {v: render_camera(integrator, ds.cameras[v], ("full", "bg", "fg")) for v in tests}
    images = {"volume": {v: np.clip(renders[v]["bg"][0], 0, 1) for v in tests}}
    for name in available_baselines():
        images[name] = {v: inpainter(name)(ds.images[v], dilate(ds.masks[v], dil)) for v in tests}
    depth = {v: renders[v]["bg"][2] for v in tests}
    # the masked pixels whose background (at the volume's depth) some training view sees unmasked
    surfaces = training_surfaces(ds, integrator) if scored else {}
    seen = {v: seen_pixels(ds, v, dilate(ds.masks[v], dil), depth[v], surfaces) for v in scored}
    rows = {}
    for name, by_view in images.items():
        r = {"psnr_mask": [], "psnr_outside": [], "residue": [], "psnr_seen": [], "psnr_unseen": []}
        for v in scored:
            region, gt = dilate(ds.masks[v], dil), ds.backgrounds[v]
            r["psnr_mask"].append(psnr(by_view[v], gt, region))
            for key, part in (("psnr_seen", seen[v]), ("psnr_unseen", region & ~seen[v])):
                r[key].append(psnr(by_view[v], gt, part) if part.any() else np.nan)
            r["psnr_outside"].append(psnr(by_view[v], gt, ~region))
            r["residue"].append(object_residue(by_view[v], ds.images[v], gt, ds.masks[v]))
        rows[name] = {k: mean_defined(x) for k, x in r.items()}  # None where no view defines it
        rows[name]["psnr_mask_views"] = [float(x) for x in r["psnr_mask"]]  # per view, in the order of "views"
        rows[name]["consistency_psnr"] = consistency(ds, tests, by_view, depth, dil)
    full_out = [psnr(np.clip(renders[v]["full"][0], 0, 1), ds.backgrounds[v], ~dilate(ds.masks[v], dil))
                for v in scored]
    rows["volume"]["views"] = [int(v) for v in scored]
    rows["volume"]["full_psnr_outside"] = float(np.mean(full_out)) if full_out else None
    # the metric's reference: the ground-truth background itself, warped the same way (what a correct
    # answer scores through the volume's depth)
    rows["volume"]["truth_consistency_psnr"] = consistency(
        ds, scored, {v: np.clip(ds.backgrounds[v], 0, 1) for v in scored}, depth, dil) if scored else None
    rows["volume"]["consistency_shares"] = consistency_shares(ds, tests, depth, dil)
    # where the background stands behind the object (a fill in the hull, the surfaces around, or a hole)
    rows["volume"]["mask_surfaces"] = mask_surfaces(ds, integrator, tests, dil, hull_min_views)
    # the background's haze in the hole and around it (mi_voldis.fit.report.background_haze)
    haze = [background_haze(integrator, ds.cameras[v], dilate(ds.masks[v], dil)) for v in tests]
    for key in ("bg_haze_mask", "bg_haze_outside"):
        rows["volume"][key] = mean_defined([h[key] for h in haze]) if haze else None
    if not scored and tests:  # a capture: the object's residue against the 2D fill of each view (no truth)
        fill = inpainter("telea")
        rows["volume"]["residue_vs_telea"] = float(np.mean([object_residue(
            images["volume"][v], ds.images[v], fill(ds.images[v], dilate(ds.masks[v], dil)), ds.masks[v])
            for v in tests]))
    rows["volume"]["seen_share"] = float(np.mean([seen[v].sum() / max(dilate(ds.masks[v], dil).sum(), 1)
                                                  for v in scored])) if scored else None
    # the foreground against the exact coverage, or on a capture against its masks: the coverage
    # sum max(w_fg, 0) and the matte the EXR's fg layer carries (what a compositor gets)
    truth = {v: ds.coverage[v] > 0.5 if ds.coverage is not None else ds.masks[v] for v in tests}
    mattes = {v: composite_channels(layer_channels(renders[v], main="full"))["fg.A"] for v in tests}
    for key, layer in (("fg_coverage_iou", {v: renders[v]["fg_coverage"] for v in tests}), ("fg_matte_iou", mattes)):
        rows["volume"][key] = float(np.mean([iou(layer[v] > 0.5, truth[v]) for v in tests])) if tests else None
    return rows, renders


def coverage_errors(photo, found, truth):
    """A picture of the foreground coverage against the truth (uint8 RGB): the photo dimmed, pixels of
    both white, the foreground's alone (false positives) red, the truth's alone (missed) blue."""
    out = 0.3 * np.clip(photo[..., :3], 0, 1)
    out[found & truth] = 1.0
    out[found & ~truth] = (1.0, 0.1, 0.1)
    out[~found & truth] = (0.2, 0.4, 1.0)
    return (out * 255).round().astype(np.uint8)


def main(argv=None):
    argv = list(argv or sys.argv[1:])
    refit = "--refit" in argv
    argv = [a for a in argv if a != "--refit"]
    sets = [argv[k + 1] for k, a in enumerate(argv) if a == "--set" and k + 1 < len(argv)]
    argv = [a for k, a in enumerate(argv) if a != "--set" and (k == 0 or argv[k - 1] != "--set")]
    if len(argv) < 3:
        raise SystemExit("usage: python -m mi_voldis.bench.strategies RUN STRATEGY OUT [MASKED_DATASET] "
                         "[--set KEY=VALUE ...] [--refit]")
    run, strategy, out = argv[:3]
    from ..data import load_dataset
    from ..fit.fields import scene_integrator
    from ..fit.state import FitState
    from ..fit.train import fit
    from ..io.images import display_to_uint8, write_png
    from ..io.run_folder import peak_rss_mib, write_json
    from ..optim.adam import Adam
    try:  # the settings first: their errors name the file, the key or the --set item
        cfg = refit_config(run, strategy, sets)
    except ValueError as e:
        raise SystemExit(f"error: {e}") from None
    with open(os.path.join(run, "config.json")) as f:
        record = json.load(f).get("dataset")
    if not isinstance(record, dict):
        raise SystemExit(f"error: {os.path.join(run, 'config.json')}: no dataset record (not a fitted run's)")
    ds = load_dataset(record["path"], record["format"], record["holdout"])
    fit_ds = load_dataset(argv[3], record["format"], record["holdout"]) if len(argv) > 3 else ds
    for dataset in dict.fromkeys([record["path"]] + argv[3:4]):
        problem = out_problem(out, run, dataset)
        if problem:
            raise SystemExit(f"error: {out}: {problem}")
    adam = Adam({}, cfg.adam_beta1, cfg.adam_beta2, warmup=cfg.lr_warmup)
    state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), adam)
    if state is None:
        raise SystemExit(f"error: {run}: no checkpoints/last.npz (fit it with --keep-checkpoints)")
    os.makedirs(out, exist_ok=True)
    # the run's own background where it was fitted with these very settings (a refit is the same
    # computation: the same full field, settings and seed); else the background is fitted again
    reuse = state.phase == "done" and len(argv) == 3 and not refit and same_settings(run, cfg)
    if not reuse:
        state.fields.pop("bg", None)
        state.hull_points = state.prior = state.prior_keys = state.occupancy = None
        state.adam.reset()
    checkpoint = os.path.join(out, "state.npz")
    state.save(checkpoint, "done" if reuse else "bg", 0)
    t0 = time.perf_counter()
    inputs, state = fit(fit_ds, checkpoint, cfg, resume=True, progress=False)
    seconds = time.perf_counter() - t0
    if reuse:
        with open(os.path.join(run, "metrics.json")) as f:
            seconds = json.load(f)["seconds"]["phase_bg"]
    os.remove(checkpoint)
    integrator, _ = scene_integrator(inputs, state)  # scored as the run's scene.xml renders it
    if ds.masks is None:  # a capture without masks: scored with the masks the background was fitted with
        ds = fit_ds
    rows, renders = evaluate(ds, integrator, cfg.hull_min_views)
    if not renders:  # nothing to score: previews of the first held-out views all the same
        from ..render.views import render_camera
        renders = {v: render_camera(integrator, ds.cameras[v], ("bg",)) for v in list(ds.test)[:PREVIEWS]}
    for v, layers in renders.items():
        write_png(os.path.join(out, f"view{v:03d}_bg.png"), display_to_uint8(np.clip(layers["bg"][0], 0, 1)))
        if "fg_coverage" in layers:
            truth = ds.coverage[v] > 0.5 if ds.coverage is not None else ds.masks[v]
            write_png(os.path.join(out, f"view{v:03d}_coverage.png"),
                      coverage_errors(ds.images[v], layers["fg_coverage"] > 0.5, truth))
    write_json(os.path.join(out, "metrics.json"), {"strategy": strategy, "seconds": seconds, "methods": rows,
                                                   "prior": state.prior, "peak_rss_mib": peak_rss_mib()})


if __name__ == "__main__":
    main()
