"""What a fitting run writes: fields (.vol), scene.xml, config, metrics, previews and a plot."""
import json
import os

import numpy as np

from ..export import previews
from ..io.images import write_png
from ..io.scene_xml import save_field, sensor_xml, write_scene
from ..metrics import dilate, iou, psnr, ssim
from ..render.views import layer_channels
from .raybank import RayBank

OCCUPANCY_FOR_RENDERING = (96, 0.02)  # cells along the longest side, density threshold


def scene_options(ctx):
    """Integrator properties of the fitted scene (samples, occupancy, scene space)."""
    opts = {"samples": ctx.cfg.max_samples, "step_size": float(ctx.step_size()),
            "occupancy_resolution": ctx.cfg.occupancy_resolution,
            "occupancy_threshold": float(ctx.occupancy_sigma())}
    for key, value in ctx.space.properties().items():
        if key != "ndc_to_world":
            opts[key] = float(value)
    return opts


def write_fields(ctx, out):
    bodies = {}
    for role in ("full", "bg"):
        s = ctx.states[role]
        bodies[role] = save_field(out, role, np.array(s.density), np.array(s.color), s.to_world, s.density_scale)
    return bodies


def write_run_scene(ctx, out, bodies, views, name="scene.xml", options=None, transforms=None):
    """scene.xml with the fields and one sensor per given dataset view."""
    sensors = [sensor_xml(c.to_world, c.fov_x, c.width, c.height, 1, c.principal)
               for c in (ctx.ds.cameras[v] for v in views)]
    opts = scene_options(ctx)
    opts.update(options or {})
    transforms = dict(transforms or {})
    if not ctx.space.is_world:
        transforms["ndc_to_world"] = ctx.space.to_world_m
    write_scene(os.path.join(out, name), bodies, opts, sensors, transforms)


def evaluate(ctx, integrator, samples=None):
    """Metrics on every held-out view, and the rendered layers of each (for previews)."""
    ds, cfg = ctx.ds, ctx.cfg
    views = list(ds.test)
    bank = RayBank(ds, views)
    rows, renders = [], {}
    dil = int(np.ceil(cfg.hull_dilation * np.hypot(*ds.size)))
    for k, v in enumerate(views):
        out = ctx.render_view(integrator, bank, k, ("composite", "full", "bg", "fg"), samples)
        renders[v] = out
        full = np.clip(out["full"][0], 0, 1)
        row = {"view": int(v), "psnr": psnr(full, ds.images[v]), "ssim": ssim(full, ds.images[v])}
        if ds.backgrounds is not None and np.isfinite(ds.backgrounds[v]).all():
            bg, gt = np.clip(out["bg"][0], 0, 1), ds.backgrounds[v]
            region = dilate(ds.masks[v], dil) if ds.masks is not None else None
            row.update(bg_psnr=psnr(bg, gt), bg_ssim=ssim(bg, gt), bg_psnr_mask=psnr(bg, gt, region),
                       bg_ssim_mask=ssim(bg, gt, region))
        truth = ds.coverage[v] > 0.5 if ds.coverage is not None else ds.masks[v] if ds.masks is not None else None
        if truth is not None:  # the layer's alpha (alpha_full - alpha_bg) and the object's coverage
            row["fg_iou"] = iou(out["fg"][1] > 0.5, truth)
            row["fg_coverage_iou"] = iou(out["fg_coverage"] > 0.5, truth)
        rows.append(row)
    summary = {key: float(np.nanmean([r[key] for r in rows])) for key in rows[0] if key != "view"} if rows else {}
    return summary, rows, renders


def write_previews(out, renders, views):
    os.makedirs(out, exist_ok=True)
    for v in views:
        for name, image in previews(layer_channels(renders[v]), ("full", "bg", "fg")).items():
            write_png(os.path.join(out, f"view{v:03d}_{name}.png"), image)


def plot_log(path, log, title):
    """Training loss and PSNR against wall-clock seconds."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    t = [r["time"] for r in log]
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.6))
    ax[0].semilogy(t, [r["loss"] for r in log], lw=0.8)
    ax[0].set_xlabel("seconds")
    ax[0].set_ylabel("training loss")
    for key, label in (("psnr", "train batch (full)"), ("psnr_bg", "train batch (bg)"), ("test_psnr", "held-out")):
        pts = [(r["time"], r[key]) for r in log if key in r]
        if pts:
            ax[1].plot(*zip(*pts), "o-" if key == "test_psnr" else "-", lw=0.8, ms=3, label=label)
    ax[1].set_xlabel("seconds")
    ax[1].set_ylabel("PSNR (dB)")
    if ax[1].get_legend_handles_labels()[0]:
        ax[1].legend()
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def peak_rss_mib():
    """Peak resident memory of this process in MiB (``VmHWM``; None where /proc is missing).

    Unlike ``ru_maxrss``, VmHWM belongs to the address space and starts afresh at ``exec``: a child
    process forked from a large parent would otherwise report the parent's peak."""
    try:
        with open("/proc/self/status") as f:
            line = next(line for line in f if line.startswith("VmHWM:"))
    except (OSError, StopIteration):
        return None
    return int(line.split()[1]) / 1024.0


def write_json(path, data):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1, default=float)
    os.replace(tmp, path)
