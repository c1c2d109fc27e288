"""Visual hull of the object: grid cells whose projections fall inside the (dilated) object masks.

Masks exclude occluders in front of the object, so a point of the object hidden by an occluder in
some view projects outside that view's mask; a cell is therefore kept when it is inside the dilated
mask in at least a fraction ``min_fraction`` of the views that see it, not necessarily all.
"""
import numpy as np

from ..cameras import pixel_of
from ..metrics import dilate


def visual_hull(points, cameras, masks, dilation_px, min_fraction):
    """Boolean per world point: inside the hull carved by ``masks`` (N, H, W) seen from ``cameras``."""
    masks = dilate(masks, dilation_px)
    seen = np.zeros(len(points), np.int32)
    inside = np.zeros(len(points), np.int32)
    for cam, mask in zip(cameras, masks):
        ix, iy, ok = pixel_of(cam, points)
        seen += ok
        hit = np.zeros(len(points), bool)
        hit[ok] = mask[iy[ok], ix[ok]]
        inside += hit
    return (seen > 0) & (inside >= min_fraction * seen)
