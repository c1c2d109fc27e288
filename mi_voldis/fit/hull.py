"""Visual hull of the object: grid cells whose projections fall inside the (dilated) object masks.

Masks exclude occluders in front of the object, so a point of the object hidden by an occluder in
some view projects outside that view's mask; a cell is therefore kept when it is inside the dilated
mask in at least a fraction ``min_fraction`` of the views that see it, not necessarily all; given
the views' depth maps, a view whose surface at the point's pixel lies nearer than the point, outside
its mask, does not vote (:func:`hull_behind_occluders`, which the background's hull adds).
"""
import numpy as np

from ..cameras import pixel_of
from ..metrics import dilate
from .visibility import seen_elsewhere


def visual_hull(points, cameras, masks, dilation_px, min_fraction, depths=None, tol=0.05):
    """Boolean per world point: inside the hull carved by ``masks`` (N, H, W) seen from ``cameras``.
    With ``depths`` (per camera a depth map or None), a camera abstains for a point outside its mask
    behind something nearer than (1 - ``tol``) times the point's distance (an occluder hides it there)."""
    masks = dilate(masks, dilation_px)
    seen = np.zeros(len(points), np.int32)
    inside = np.zeros(len(points), np.int32)
    for k, (cam, mask) in enumerate(zip(cameras, masks)):
        ix, iy, ok = pixel_of(cam, points)
        hit = np.zeros(len(points), bool)
        hit[ok] = mask[iy[ok], ix[ok]]
        depth = None if depths is None else depths[k]
        if depth is not None:
            dist = np.linalg.norm(points - np.asarray(cam.to_world)[:3, 3], axis=1)
            hidden = np.zeros(len(points), bool)
            hidden[ok] = depth[iy[ok], ix[ok]] < (1.0 - tol) * dist[ok]  # NaN (nothing there): votes
            ok &= hit | ~hidden
        seen += ok
        inside += hit
    return (seen > 0) & (inside >= min_fraction * seen)


def hull_behind_occluders(points, cameras, masks, dilation_px, min_fraction, depths, tol=0.05):
    """Boolean per world point: in the hull once the views with an occluder in front of it abstain
    (``depths``: per camera its depth map or None) and on a surface some view of ``depths`` sees inside
    its mask. Behind a surface (in the floor, a wall) every view abstains: the second test keeps such
    points out."""
    voted = visual_hull(points, cameras, masks, dilation_px, min_fraction, depths, tol)
    have = [k for k, d in enumerate(depths) if d is not None]
    shown = seen_elsewhere(points, [cameras[k] for k in have], [depths[k] for k in have], [~masks[k] for k in have])
    return voted & shown
