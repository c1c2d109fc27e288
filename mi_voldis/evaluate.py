"""Removal scored as the peers score it (SPIn-NeRF's protocol) on views with a ground-truth background.

A view counts when the dataset gives its background without the object (SPIn-NeRF's test views, whose
photos were taken after the object was carried away, or the ``background_path`` of a transforms.json)
and marks where the object stood. The background layer rendered from the run's fields is compared
with it, display-encoded in [0, 1], over three regions, as the removal literature reports them:

* ``image``: every pixel;
* ``mask``: the object's mask dilated by ``dilation`` of the image diagonal;
* ``bbox``: the bounding box of that dilated mask (both images cropped to it).

PSNR and SSIM (:mod:`mi_voldis.metrics`) in each; with a ``perceptual`` callable (LPIPS,
:mod:`mi_voldis.lpips`), that too on the whole image and on the box crop (at least 64 pixels a side).
"""
import numpy as np

from .metrics import diagonal_pixels, dilate, psnr, ssim
from .render.views import render_camera

REGIONS = ("image", "mask", "bbox")
LPIPS_MIN = 64  # pixels a side below which LPIPS (AlexNet) is not computed


def scored_views(ds):
    """Test views with a finite ground-truth background and an object mask."""
    if ds.backgrounds is None or ds.masks is None:
        return []
    return [int(v) for v in ds.test if np.isfinite(ds.backgrounds[v]).all() and ds.masks[v].any()]


def bbox(region):
    ys, xs = np.nonzero(region)
    return slice(ys.min(), ys.max() + 1), slice(xs.min(), xs.max() + 1)


def score_view(render, truth, mask, dil, perceptual=None):
    """{metric_region: value} of one view (see the module docstring)."""
    region = dilate(mask, dil)
    box = bbox(region)
    out = {"psnr_image": psnr(render, truth), "ssim_image": ssim(render, truth),
           "psnr_mask": psnr(render, truth, region), "ssim_mask": ssim(render, truth, region),
           "psnr_bbox": psnr(render[box], truth[box])}
    crop = render[box].shape[:2]
    out["ssim_bbox"] = ssim(render[box], truth[box]) if min(crop) > 10 else None  # SSIM's window is 11 pixels
    if perceptual is not None:  # AlexNet's stride and pooling need 64 pixels a side
        out["lpips_image"] = float(perceptual(render, truth)) if min(render.shape[:2]) >= LPIPS_MIN else None
        out["lpips_bbox"] = float(perceptual(render[box], truth[box])) if min(crop) >= LPIPS_MIN else None
    return out


def evaluate_removal(integrator, ds, dilation=0.01, perceptual=None):
    """Per-view scores and their means over :func:`scored_views` of the ``bg`` layer of ``integrator``."""
    views = scored_views(ds)
    dil = diagonal_pixels(dilation, ds.size)
    rows = {}
    for v in views:
        render = np.clip(render_camera(integrator, ds.cameras[v], ("bg",))["bg"][0], 0, 1)
        rows[ds.names[v]] = score_view(render, ds.backgrounds[v], ds.masks[v], dil, perceptual)
    keys = next(iter(rows.values())).keys() if rows else ()
    mean = {k: float(np.mean([r[k] for r in rows.values() if r[k] is not None]))
            if any(r[k] is not None for r in rows.values()) else None for k in keys}
    return {"views": len(rows), "mean": mean, "per_view": rows,
            "regions": {"image": "every pixel", "mask": f"object mask dilated by {100 * dilation:g}% of the diagonal",
                        "bbox": "bounding box of the dilated mask"}}
