"""What a fit is worth: metrics on the held-out views (against photographs and, where the dataset
has it, ground truth), and their previews."""
import os

import numpy as np

from ..compositing import composite_channels
from ..export import previews
from ..io.images import write_png
from ..metrics import dilate, iou, psnr, score_dilation, ssim
from ..render.surface import front_weight
from ..render.views import layer_channels, render_camera


def evaluate(ds, integrator):
    """Metrics on every held-out view, and the rendered layers of each (for previews). Background
    metrics inside the masks use masks dilated by :data:`~mi_voldis.metrics.SCORE_DILATION`; ``haze`` is
    the mean share of a ray's weight the full field spends well in front of the surface it shows
    (:func:`~mi_voldis.render.surface.front_weight`), ``bg_haze_mask`` / ``bg_haze_outside`` the
    background's inside the dilated masks and outside them (:func:`background_haze`)."""
    rows, renders = [], {}
    dil = score_dilation(ds.size)
    for v in ds.test:
        out = render_camera(integrator, ds.cameras[v], ("composite", "full", "bg", "fg"))
        renders[v] = out
        full = np.clip(ds.as_photographed(out["full"]), 0, 1)
        row = {"view": int(v), "psnr": psnr(full, ds.images[v]), "ssim": ssim(full, ds.images[v]),
               "samples_per_ray": float(out["evaluated"].mean())}
        front, hit = front_weight(integrator, ds.cameras[v])  # the full field's haze (render.surface)
        row["haze"] = float(front[hit].mean()) if hit.any() else float("nan")
        if ds.masks is not None:  # the background's, inside the masks and outside them
            row.update(background_haze(integrator, ds.cameras[v], dilate(ds.masks[v], dil)))
        if ds.backgrounds is not None and np.isfinite(ds.backgrounds[v]).all():
            bg, gt = np.clip(ds.as_photographed(out["bg"]), 0, 1), ds.backgrounds[v]
            region = dilate(ds.masks[v], dil) if ds.masks is not None else None
            row.update(bg_psnr=psnr(bg, gt), bg_ssim=ssim(bg, gt), bg_psnr_mask=psnr(bg, gt, region),
                       bg_ssim_mask=ssim(bg, gt, region))
        truth = ds.coverage[v] > 0.5 if ds.coverage is not None else ds.masks[v] if ds.masks is not None else None
        if truth is not None:  # the object's coverage sum max(w_fg, 0), and the matte the EXR's fg layer carries
            row["fg_coverage_iou"] = iou(out["fg_coverage"] > 0.5, truth)
            row["fg_matte_iou"] = iou(composite_channels(layer_channels(out))["fg.A"] > 0.5, truth)
        rows.append(row)
    summary = {key: mean_defined([r[key] for r in rows]) for key in rows[0] if key != "view"} if rows else {}
    return summary, rows, renders


def background_haze(integrator, camera, region):
    """The background field's haze (:func:`~mi_voldis.render.surface.front_weight`) through ``camera``,
    averaged over the rays that end on something inside ``region`` (H, W bool: the dilated mask, where
    the object was) and outside it: {'bg_haze_mask', 'bg_haze_outside'} (NaN where no such ray). In
    the hole the background should stand on surfaces as it does around it, so the first is no higher
    than the second; above it, a veil hangs where the object stood."""
    front, hit = front_weight(integrator, camera, layer="bg")
    out = {}
    for key, part in (("bg_haze_mask", region & hit), ("bg_haze_outside", ~region & hit)):
        out[key] = float(front[part].mean()) if part.any() else float("nan")
    return out


def mean_defined(values):
    """Mean over the views where a metric is defined (not NaN, e.g. an IoU where neither mask has a
    pixel); None where it is defined on none."""
    values = [v for v in values if v == v]
    return float(np.mean(values)) if values else None


def write_previews(out, renders, views, backdrop=None):
    """PNG previews of the held-out ``views``' layers (:func:`~mi_voldis.export.previews`), over the
    dataset's ``backdrop`` colour where it has one, as its photographs are."""
    os.makedirs(out, exist_ok=True)
    for v in views:
        linear = composite_channels(layer_channels(renders[v]))
        for name, image in previews(linear, ("full", "bg", "fg"), backdrop).items():
            write_png(os.path.join(out, f"view{v:03d}_{name}.png"), image)
