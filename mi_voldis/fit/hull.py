"""Visual hull of the object: grid cells whose projections fall inside the (dilated) object masks.

Masks exclude occluders in front of the object, so a point of the object hidden by an occluder in
some view projects outside that view's mask; a cell is therefore kept when it is inside the dilated
mask in at least a fraction ``min_fraction`` of the views that see it, not necessarily all.
"""
import numpy as np

from ..metrics import dilate


def project(camera, points):
    """Pixel coordinates (x, y) and camera-frame depth of world points under a Mitsuba camera."""
    inv = np.linalg.inv(np.asarray(camera.to_world, np.float64))
    pc = points @ inv[:3, :3].T + inv[:3, 3]
    t = 2 * np.tan(np.radians(camera.fov_x) / 2)
    z = pc[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        px = camera.width * (0.5 - camera.principal[0] - pc[:, 0] / (z * t))
        py = camera.height * (0.5 - camera.principal[1] - pc[:, 1] / (z * t * camera.height / camera.width))
    return px, py, z


def visual_hull(points, cameras, masks, dilation_px, min_fraction):
    """Boolean per world point: inside the hull carved by ``masks`` (N, H, W) seen from ``cameras``."""
    masks = dilate(masks, dilation_px)
    seen = np.zeros(len(points), np.int32)
    inside = np.zeros(len(points), np.int32)
    for cam, mask in zip(cameras, masks):
        px, py, z = project(cam, points)
        ix, iy = np.floor(px).astype(np.int64), np.floor(py).astype(np.int64)
        ok = (z > 0) & (ix >= 0) & (ix < cam.width) & (iy >= 0) & (iy < cam.height)
        seen += ok
        hit = np.zeros(len(points), bool)
        hit[ok] = mask[iy[ok], ix[ok]]
        inside += hit
    return (seen > 0) & (inside >= min_fraction * seen)
