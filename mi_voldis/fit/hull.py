"""Visual hull of the object: grid cells whose projections fall inside the (dilated) object masks.

Masks exclude occluders in front of the object, so a point of the object hidden by an occluder in
some view projects outside that view's mask; a cell is therefore kept when it is inside the dilated
mask in at least a fraction ``min_fraction`` of the views that see it, not necessarily all; given
the views' depth maps, a view whose surface at the point's pixel lies nearer than the point, outside
its mask, does not vote (:func:`hull_behind_occluders`, which the background's hull adds).
"""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..cameras import DevicePoints, device_image
from ..metrics import diagonal_pixels, dilate
from .visibility import seen_elsewhere


def visual_hull(points, cameras, masks, dilation_px, min_fraction, depths=None, tol=0.05):
    """Boolean per world point: inside the hull carved by ``masks`` (N, H, W) seen from ``cameras``.
    With ``depths`` (per camera a depth map or None), a camera abstains for a point outside its mask
    behind something nearer than (1 - ``tol``) times the point's distance (an occluder hides it there).
    Each view's vote is a kernel over every point (:class:`~mi_voldis.cameras.DevicePoints`)."""
    if len(points) == 0:
        return np.zeros(0, bool)
    masks = dilate(masks, dilation_px)
    at = DevicePoints(points)
    seen, inside = dr.zeros(mi.UInt32, at.count), dr.zeros(mi.UInt32, at.count)
    for k, (cam, mask) in enumerate(zip(cameras, masks)):
        index, ok = at.pixel_of(cam)
        hit = ok & dr.gather(mi.Bool, device_image(mask, mi.Bool), index, ok)
        depth = None if depths is None else depths[k]
        if depth is not None:  # NaN (nothing there) is not nearer: the view votes
            hidden = dr.gather(mi.Float64, device_image(depth, mi.Float64), index, ok) < (1.0 - tol) * at.distance(cam)
            ok &= hit | ~hidden
        seen += dr.select(ok, 1, 0)
        inside += dr.select(hit, 1, 0)
        dr.eval(seen, inside)
    return ((seen > 0) & (mi.Float64(inside) >= min_fraction * mi.Float64(seen))).numpy().astype(bool)


def hull_behind_occluders(points, cameras, masks, dilation_px, min_fraction, depths, tol=0.05):
    """Boolean per world point: in the hull once the views with an occluder in front of it abstain
    (``depths``: per camera its depth map or None) and on a surface some view of ``depths`` sees inside
    its mask. Behind a surface (in the floor, a wall) every view abstains: the second test keeps such
    points out."""
    voted = visual_hull(points, cameras, masks, dilation_px, min_fraction, depths, tol)
    have = [k for k, d in enumerate(depths) if d is not None]
    voted[voted] = seen_elsewhere(np.asarray(points)[voted], [cameras[k] for k in have], [depths[k] for k in have],
                                  [~masks[k] for k in have])  # per point: asked of the voted ones alone
    return voted


def check_hull(inputs, resolution=48):
    """Refuses, before any fitting, a dataset whose object hull is empty, which the background phase
    needs after the whole full-scene phase: no training view has an object mask (masks only on test
    views, SPIn-NeRF's ``label/`` missing), or no point of a ``resolution``^3 lattice over the scene box
    lies in the hull the masked training views carve (masks, poses or intrinsics that disagree). Raises
    :class:`~mi_voldis.data.types.DatasetError` naming the dataset; nothing to check without masks."""
    from ..data.types import DatasetError
    ds, cfg = inputs.ds, inputs.cfg
    if ds.masks is None:
        return
    views = ds.masked_train
    if len(views) == 0:
        tests = int(np.sum(ds.masked[ds.test])) if ds.masked is not None else 0
        raise DatasetError(f"{ds.root}: no training view has an object mask ({len(ds.train)} training views, "
                           f"{tests} masked test views): the object's hull and the background are learnt from the "
                           "masked training views")
    axes = [np.linspace(a, b, resolution) for a, b in zip(inputs.box.lo, inputs.box.hi)]
    lattice = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    with np.errstate(all="ignore"):  # a contracted box's outer faces lie at infinity
        points = inputs.space.to_world_np(lattice)
    points = points[np.all(np.isfinite(points), axis=1)]
    dilation = diagonal_pixels(cfg.hull_dilation, ds.size)
    if not visual_hull(points, [ds.cameras[v] for v in views], ds.masks[views], dilation, cfg.hull_min_views).any():
        raise DatasetError(f"{ds.root}: the object's visual hull is empty: no point of the scene box projects inside "
                           f"the object masks of enough of the {len(views)} masked training views that see it "
                           f"(hull_min_views {cfg.hull_min_views}); the masks, poses or intrinsics disagree")
