"""Removal: the background volume on its own (paper: removal == the background in isolation).

Measured against the ground truth where the dataset has it, and against 2D inpainting per view with
the same dilated masks (:data:`~mi_voldis.inpaint2d.BASELINES`: OpenCV's Telea and Navier-Stokes,
OpenCV contrib's FSR where installed): PSNR / SSIM inside the masks, the
object's residue (:func:`mi_voldis.metrics.object_residue`: the share of its pixels still closer to its
own colour than to the true background), and
view-to-view consistency: each held-out view's inpainting, reprojected into its nearest held-out
neighbour with the background's depth (bilinear, z-tested in both views), compared there inside the
mask (a per-view 2D method has no reason to agree with itself across views; a volume does by
construction).
"""
import numpy as np

from ..cameras import pixel_rays, project
from ..inpaint2d import available_baselines, inpainter
from ..metrics import diagonal_pixels, dilate, object_residue, psnr, ssim


def bilinear_taps(h, w, x, y):
    """The four pixels of an (h, w) image that bilinear interpolation at continuous pixel indices (x, y)
    (n,) in [0, w - 1] x [0, h - 1] mixes: [(iy, ix, weight) ...]."""
    x0 = np.clip(np.floor(x), 0, max(w - 2, 0)).astype(int)
    y0 = np.clip(np.floor(y), 0, max(h - 2, 0)).astype(int)
    x1, y1 = np.minimum(x0 + 1, w - 1), np.minimum(y0 + 1, h - 1)
    fx, fy = x - x0, y - y0
    return [(y0, x0, (1 - fy) * (1 - fx)), (y0, x1, (1 - fy) * fx), (y1, x0, fy * (1 - fx)), (y1, x1, fy * fx)]


KEPT, OUTSIDE, NEARER, FARTHER = range(4)  # how a pixel of one view fares in another (depth_test)


def depth_test(depth_a, cam_a, cam_b, depth_b, tolerance=0.03):
    """Where each pixel of camera b, its point at ``depth_b`` (distance along b's ray), lands in view a
    and whether a sees that point: continuous pixel indices (x, y) into a, (n,) each, and a code per
    pixel: KEPT; OUTSIDE (b has no depth there or the point leaves a's frame); NEARER / FARTHER (at one
    of the four pixels around it a's depth is nearer / farther than the point's distance by more than
    ``tolerance`` of it: an occluder in either view, a silhouette, or geometry the views disagree on)."""
    hb, wb = depth_b.shape
    py, px = np.mgrid[0:hb, 0:wb]
    o, d = pixel_rays(cam_b, px.ravel() + 0.5, py.ravel() + 0.5)
    zb = depth_b.ravel().astype(np.float64)
    p = o + np.where(np.isfinite(zb) & (zb > 0), zb, 0.0)[:, None] * d
    u, v, z = project(cam_a, p)
    h, w = depth_a.shape
    inside = np.isfinite(zb) & (zb > 0) & (z > 0) & (u >= 0.5) & (u <= w - 0.5) & (v >= 0.5) & (v <= h - 0.5)
    x, y = np.where(inside, u - 0.5, 0.0), np.where(inside, v - 0.5, 0.0)
    taps = bilinear_taps(h, w, x, y)
    dist = np.linalg.norm(p - np.asarray(cam_a.to_world, np.float64)[:3, 3], axis=1)
    nearer = np.any([depth_a[iy, ix] < (1 - tolerance) * dist for iy, ix, _ in taps], axis=0)
    farther = np.any([~(depth_a[iy, ix] <= (1 + tolerance) * dist) for iy, ix, _ in taps], axis=0)  # NaN too
    code = np.where(~inside, OUTSIDE, np.where(nearer, NEARER, np.where(farther, FARTHER, KEPT)))
    return x, y, code


def reproject(image_a, depth_a, cam_a, cam_b, depth_b, tolerance=0.03):
    """View a's image seen from camera b (backward warp): sampled bilinearly where :func:`depth_test`
    keeps b's pixel, NaN elsewhere (so an occluder in either view, or its silhouette, is not scored as a
    disagreement). (H_b, W_b, 3)."""
    x, y, code = depth_test(depth_a, cam_a, cam_b, depth_b, tolerance)
    sample = sum(wt[:, None] * image_a[iy, ix] for iy, ix, wt in bilinear_taps(*image_a.shape[:2], x, y))
    return np.where((code == KEPT)[:, None], sample, np.nan).reshape(*depth_b.shape, 3).astype(np.float32)


def nearest_other(ds, views, v):
    """The view of ``views`` other than ``v`` whose camera is nearest to v's (None if there is none)."""
    others = [u for u in views if u != v]
    if not others:
        return None
    pos = np.array([ds.cameras[u].to_world[:3, 3] for u in others])
    return others[int(np.argmin(np.linalg.norm(pos - ds.cameras[v].to_world[:3, 3], axis=1)))]


def consistency(ds, views, images, depth, dil):
    """Mean PSNR of each of ``views``' inpainting (``images[v]``) seen from its nearest other view u of
    ``views`` through the depths (:func:`reproject`: u's pixel at ``depth[u]``, sampled in v where v's
    ``depth[v]`` sees the same point), compared there with u's own inpainting inside u's mask (dilated by
    ``dil`` pixels); None with fewer than two views."""
    values = []
    for v in views:
        u = nearest_other(ds, views, v)
        if u is None:
            continue
        warped = reproject(images[v], depth[v], ds.cameras[v], ds.cameras[u], depth[u])
        region = dilate(ds.masks[u], dil) & np.isfinite(warped).all(axis=-1)
        if region.any():
            values.append(psnr(warped[region], images[u][region]))
    return float(np.mean(values)) if values else None


def consistency_shares(ds, views, depth, dil):
    """How :func:`depth_test` sorts the dilated masks' pixels in :func:`consistency`, mean over the view
    pairs: ``{"compared", "outside", "nearer", "farther"}`` shares (summing to 1); a property of the
    depths, the same for every image. None with fewer than two views."""
    shares = []
    for v in views:
        u = nearest_other(ds, views, v)
        if u is None:
            continue
        code = depth_test(depth[v], ds.cameras[v], ds.cameras[u], depth[u])[2]
        region = dilate(ds.masks[u], dil).ravel()
        shares.append([(region & (code == c)).sum() / max(region.sum(), 1)
                       for c in (KEPT, OUTSIDE, NEARER, FARTHER)])
    if not shares:
        return None
    return dict(zip(("compared", "outside", "nearer", "farther"), map(float, np.mean(shares, axis=0))))


def run(run, output, progress=True):
    ds = run.dataset
    integrator = run.integrator(mode="bg")
    renders = output.write_views(integrator, main="bg")
    output.write_scene({"full": run.fields["full"], "bg": run.fields["bg"]}, mode="bg")
    if ds.masks is None:
        return output.finish({"task": "removal", "note": "dataset has no object masks: nothing to remove"})
    dilation = output.settings.mask_dilation
    dil = diagonal_pixels(dilation, ds.size)
    baselines = available_baselines()
    methods = {"volume": {}, **{name: {} for name in baselines}}
    depth = {}
    for v in ds.test:
        region = dilate(ds.masks[v], dil)
        methods["volume"][v] = np.clip(renders[v]["bg"][0], 0, 1)
        for name in baselines:
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
