"""Which masked pixels of a held-out view show background that some training view sees unmasked.

The masked loss L_bg can only reconstruct that part (:mod:`mi_voldis.fit.visibility`); the rest comes
from a prior. Splitting the in-mask score by it checks that the masked loss does its part and shows
what the prior adds. A held-out pixel's background point is where the ground-truth-free background
field puts it: its depth along the pixel's ray.
"""
import numpy as np

from ..fit.visibility import pixel_points, seen_elsewhere
from ..render.surface import median_depth


def training_surfaces(ds, integrator, count=24):
    """Median depth maps of the full field for up to ``count`` masked training views spread over the set
    (NaN where a ray ends on nothing), keyed by view."""
    views = list(ds.masked_train)
    pick = np.unique(np.linspace(0, len(views) - 1, min(count, len(views))).round().astype(int))
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
