"""Removal: the background volume on its own (paper: removal == the background in isolation).

Measured against the ground truth where the dataset has it, and against 2D inpainting per view with
the same dilated masks (:data:`~mi_voldis.inpaint2d.BASELINES`: OpenCV's Telea and Navier-Stokes,
OpenCV contrib's FSR): PSNR / SSIM inside the masks, the
object's residue (:func:`mi_voldis.metrics.object_residue`: the share of its pixels still closer to its
own colour than to the true background), and
view-to-view consistency: each held-out view's inpainting, reprojected into its nearest held-out
neighbour with the background's depth, compared there inside the mask (a per-view 2D method has no
reason to agree with itself across views; a volume does by construction).
"""
import numpy as np

from ..cameras import pixel_rays, project
from ..inpaint2d import BASELINES, inpainter
from ..metrics import dilate, object_residue, psnr, ssim


def reproject(image_a, depth_a, cam_a, cam_b):
    """Warp view a's pixels (with depths along its rays) into camera b: (H, W, 3) image, NaN where
    nothing lands (nearest pixel, no z-test)."""
    h, w = depth_a.shape
    py, px = np.mgrid[0:h, 0:w]
    o, d = pixel_rays(cam_a, px.ravel() + 0.5, py.ravel() + 0.5)
    u, v, z = project(cam_b, o + depth_a.reshape(-1, 1) * d)
    ok = (z > 0) & (u >= 0) & (u < cam_b.width) & (v >= 0) & (v < cam_b.height) & (depth_a.ravel() > 0)
    out = np.full((cam_b.height, cam_b.width, 3), np.nan, np.float32)
    out[v[ok].astype(int), u[ok].astype(int)] = image_a.reshape(-1, 3)[ok]
    return out


def consistency(ds, views, images, depth, dil):
    """Mean PSNR of each of ``views``' inpainting (``images[v]``) warped with ``depth[v]`` into its nearest
    other view of ``views`` and compared there inside that view's mask (dilated by ``dil`` pixels);
    None with fewer than two views."""
    values = []
    for v in views:
        others = [u for u in views if u != v]
        if not others:
            continue
        pos = np.array([ds.cameras[u].to_world[:3, 3] for u in others])
        u = others[int(np.argmin(np.linalg.norm(pos - ds.cameras[v].to_world[:3, 3], axis=1)))]
        warped = reproject(images[v], depth[v], ds.cameras[v], ds.cameras[u])
        region = dilate(ds.masks[u], dil) & np.isfinite(warped).all(axis=-1)
        if region.any():
            values.append(psnr(warped[region], images[u][region]))
    return float(np.mean(values)) if values else None


def run(run, output, progress=True):
    ds = run.dataset
    integrator = run.integrator(mode="bg")
    renders = output.write_views(integrator, main="bg")
    output.write_scene({"full": run.fields["full"], "bg": run.fields["bg"]}, mode="bg")
    if ds.masks is None:
        return output.finish({"task": "removal", "note": "dataset has no object masks: nothing to remove"})
    dilation = output.settings.mask_dilation
    dil = int(np.ceil(dilation * np.hypot(*ds.size)))
    methods = {"volume": {}, **{name: {} for name in BASELINES}}
    depth = {}
    for v in ds.test:
        region = dilate(ds.masks[v], dil)
        methods["volume"][v] = np.clip(renders[v]["bg"][0], 0, 1)
        for name in BASELINES:
            methods[name][v] = inpainter(name)(ds.images[v], region)
        depth[v] = renders[v]["bg"][2]
    rows = {}
    for name, images in methods.items():
        row = {"psnr_mask": [], "ssim_mask": [], "psnr": [], "residue": []}
        for v in ds.test:
            region = dilate(ds.masks[v], dil)
            if ds.backgrounds is not None and np.isfinite(ds.backgrounds[v]).all():
                gt = ds.backgrounds[v]
                row["psnr_mask"].append(psnr(images[v], gt, region))
                row["ssim_mask"].append(ssim(images[v], gt, region))
                row["psnr"].append(psnr(images[v], gt))
                residue = object_residue(images[v], ds.images[v], gt, ds.masks[v])
                if np.isfinite(residue):
                    row["residue"].append(residue)
        rows[name] = {k: float(np.mean(vals)) if vals else None for k, vals in row.items()}
        rows[name]["consistency_psnr"] = consistency(ds, list(ds.test), images, depth, dil)
    output.finish({"task": "removal", "methods": rows,
                   "note": f"in-mask = inside the masks dilated by {100 * dilation:g}% of the image diagonal"})
