"""Which masked pixels of a held-out view show background that some training view sees unmasked.

The masked loss L_bg can only reconstruct that part (:mod:`mi_voldis.fit.visibility`); the rest comes
from a prior. Splitting the in-mask score by it checks that the masked loss does its part and shows
what the prior adds. A held-out pixel's background point is where the ground-truth-free background
field puts it: its depth along the pixel's ray.
"""
import numpy as np

from ..data.types import spread
from ..fit.hull import visual_hull
from ..fit.visibility import pixel_points, seen_elsewhere
from ..metrics import dilate
from ..render.surface import median_depth


def training_surfaces(ds, integrator, count=24):
    """Median depth maps of the full field for up to ``count`` masked training views spread over the set
    (NaN where a ray ends on nothing), keyed by view."""
    views = list(ds.masked_train)
    pick = spread(len(views), count)
    out = {}
    for v in (views[k] for k in pick):
        depth, hit = median_depth(integrator, ds.cameras[v])
        out[v] = np.where(hit, depth, np.nan)
    return out


def seen_pixels(ds, view, region, depth, surfaces, tol=0.03):
    """(H, W) bool: the pixels of ``region`` whose point at ``depth`` (the background's depth map of
    held-out ``view``) some view of ``surfaces`` (view -> full-field depth map) sees outside its mask."""
    pixels = np.flatnonzero(region & np.isfinite(depth))
    out = np.zeros(region.shape, bool)
    if not len(pixels):
        return out
    views = list(surfaces)
    seen = seen_elsewhere(pixel_points(ds.cameras[view], depth, pixels), [ds.cameras[u] for u in views],
                          [surfaces[u] for u in views], [ds.masks[u] for u in views], tol=tol)
    out.reshape(-1)[pixels[seen]] = True
    return out


def mask_surfaces(ds, integrator, views, dilation_px, hull_min_views):
    """Where the background stands behind the object, over the masks of held-out ``views``: the share
    of masked pixels whose background median point lies inside the object's visual hull (from the
    training masks, grown by ``dilation_px``, in ``hull_min_views`` of the views that see it),
    and the median distances along the rays of the background's median points, of the full field's
    there (the object) and of the full field's on the ring between the masks grown by ``dilation_px``
    and by twice that (the surfaces around the object). A background that continues the surfaces
    around the object ends near the ring's distance; a fill that stands where the object stood ends
    inside the hull, nearer; a hole in the surfaces behind ends far behind the ring."""
    cams, masks = [ds.cameras[u] for u in ds.masked_train], ds.masks[ds.masked_train]
    inside, bg, obj, ring = [], [], [], []
    for v in views:
        mask = ds.masks[v]
        d_bg, hit_bg = median_depth(integrator, ds.cameras[v], layer="bg")
        d_full, hit_full = median_depth(integrator, ds.cameras[v])
        pixels = np.flatnonzero(mask & hit_bg)
        if len(pixels):
            points = pixel_points(ds.cameras[v], d_bg, pixels)
            inside.append(visual_hull(points, cams, masks, dilation_px, hull_min_views))
            bg.append(d_bg.reshape(-1)[pixels])
        obj.append(d_full[mask & hit_full])
        around = dilate(mask, 2 * dilation_px) & ~dilate(mask, dilation_px) & hit_full
        ring.append(d_full[around])

    def median(parts):
        values = np.concatenate(parts) if parts else np.zeros(0)
        return float(np.median(values)) if len(values) else None
    return {"in_hull": float(np.mean(np.concatenate(inside))) if inside else None,
            "background": median(bg), "object": median(obj), "ring": median(ring)}
