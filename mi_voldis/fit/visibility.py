"""Which background points behind the object some other training view sees, unmasked.

A world point X is *in view* of view j (:func:`in_view`) when it projects into view j's image outside
its object mask and nothing stands in front of it there: the full field's depth at that pixel is not
nearer than X (relative tolerance ``tol``); it is *seen* (:func:`seen_elsewhere`) when that depth
also ends at X, on its surface. What some view sees is what the paper's masked loss can reconstruct; the rest
needs a prior (:mod:`mi_voldis.fit.lift`).
"""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..cameras import DevicePoints, device_image, pixel_of, pixel_rays
from ..inpaint2d import fill_disparity
from ..metrics import diagonal_pixels, dilate


def in_view(points, cameras, depths, masks, tol=0.05):
    """Bool per world point (n, 3): some camera of ``cameras`` has it in its image, outside its mask
    ``masks[j]``, with nothing nearer than (1 - ``tol``) times its distance in front of it there (its
    full-field depth map ``depths[j]``): points in front of surfaces and just inside them count; points
    behind an occluder do not."""
    if len(points) == 0:
        return np.zeros(0, bool)
    out, at = dr.zeros(mi.Bool, len(points)), DevicePoints(points)
    for cam, depth, mask in zip(cameras, depths, masks):
        index, ok = at.pixel_of(cam)
        ok &= ~dr.gather(mi.Bool, device_image(mask, mi.Bool), index, ok)
        # NaN depth (nothing there) is not nearer: in view
        ok &= ~(dr.gather(mi.Float64, device_image(depth, mi.Float64), index, ok) < (1.0 - tol) * at.distance(cam))
        out |= ok
        dr.eval(out)
    return out.numpy().astype(bool)


def seen_elsewhere(points, cameras, depths, masks, images=None, tol=0.03):
    """Bool per world point (n, 3): seen unmasked by some camera of ``cameras``, given each camera's
    full-field depth map ``depths[j]`` (distance along its rays) and mask ``masks[j]``; with ``images``,
    also the mean colour of the pixels that see each point (n, 3) (NaN where none does)."""
    if len(points) == 0:
        return np.zeros(0, bool) if images is None else (np.zeros(0, bool), np.zeros((0, 3)))
    seen, count = dr.zeros(mi.Bool, len(points)), dr.zeros(mi.Float64, len(points))
    total = [dr.zeros(mi.Float64, len(points)) for _ in range(3)]
    at = DevicePoints(points)
    for j, (cam, depth, mask) in enumerate(zip(cameras, depths, masks)):
        index, ok = at.pixel_of(cam)
        ok &= ~dr.gather(mi.Bool, device_image(mask, mi.Bool), index, ok)
        dist = at.distance(cam)
        ok &= dr.abs(dr.gather(mi.Float64, device_image(depth, mi.Float64), index, ok) - dist) <= tol * dist
        seen |= ok
        if images is not None:
            image = device_image(images[j], mi.Float64)
            for c in range(3):
                total[c] += dr.gather(mi.Float64, image, index * 3 + c, ok)
            count += dr.select(ok, 1.0, 0.0)
        dr.eval(seen, count, total)
    seen = seen.numpy().astype(bool)
    if images is None:
        return seen
    with np.errstate(invalid="ignore", divide="ignore"):
        return seen, np.stack([t.numpy() for t in total], axis=1) / count.numpy()[:, None]


def pixel_points(camera, depth, pixels):
    """World points (n, 3) of a depth map (H, W, distance along each pixel-centre ray) at flat pixel
    indices ``pixels``."""
    py, px = np.divmod(np.asarray(pixels), camera.width)
    o, d = pixel_rays(camera, px + 0.5, py + 0.5)
    return o + depth.reshape(-1)[pixels, None] * d


def hidden_depth(camera, depth, mask, hole, ring=0.03):
    """The depth of the surface ``mask`` hides in ``camera``'s view: the full-field depth map ``depth``
    (distance along the rays, NaN where a ray ends on nothing) filled in ``hole`` (the mask grown) as
    disparity (:func:`~mi_voldis.inpaint2d.fill_disparity`), from the pixels around it that stand no
    nearer than the object: whatever is in front of it within ``ring`` of the image diagonal (a pole
    before the object) joins the hole (:func:`~mi_voldis.fit.guide.inpainting_hole`), as it does for
    the colour prior; its depth would put the hidden surface in front of the object. None where
    nothing around the hole has a depth."""
    from .guide import inpainting_hole
    hit = np.isfinite(depth)
    around = diagonal_pixels(ring, depth.shape)
    hole = inpainting_hole(hole, np.where(hit, depth, 0.0), hit, np.asarray(mask, bool), around)
    known = hit & ~hole
    if not known.any() or not hole.any():
        return None
    return fill_disparity(np.where(known, depth, np.nan), hole, known, camera=camera)


def hidden_surface_side(points, cameras, depths, masks, grow=0, margin=0.05, behind=0.25):
    """Three Bools per world point (n, 3), by the vote of the views: in front of the surface the object
    hides, far behind it, and behind it (at or beyond it, far or not).

    In each view j whose mask ``masks[j]`` (grown by ``grow`` pixels: edge pixels mix the object in)
    the point projects into, the surface behind the object is taken to continue the surfaces around the
    mask: the full-field depth map ``depths[j]`` (distance along the rays, NaN where a ray ends on
    nothing) filled in the mask as disparity from what stands no nearer than the object
    (:func:`hidden_depth`: planes exactly), d_j. The point, at distance t, is in front there when
    t < (1 - ``margin``) d_j, behind when t >= d_j and far behind when t > (1 + ``behind``) d_j; it is
    so when it is so in more than half of the views that have it in their masks. On a masked ray
    nothing but the object stands before that surface, so space in front is the object's or empty (a
    background drawn there is a veil before the hidden surface: haze in the hole); space far behind
    is hidden by it, and a background there is seen through the hole wherever the surface is not yet
    opaque."""
    points = np.asarray(points, np.float64)
    front, back, beyond, votes = (np.zeros(len(points)) for _ in range(4))
    for cam, depth, mask in zip(cameras, depths, masks):
        hole = dilate(mask, grow) if grow else np.asarray(mask, bool)
        filled = hidden_depth(cam, depth, mask, hole)
        if filled is None:
            continue
        ix, iy, ok = pixel_of(cam, points)
        ok[ok] &= hole[iy[ok], ix[ok]]
        dist = np.linalg.norm(points[ok] - cam.to_world[:3, 3], axis=1)
        surface = filled[iy[ok], ix[ok]]
        votes[ok] += 1.0
        front[ok] += dist < (1.0 - margin) * surface
        back[ok] += dist > (1.0 + behind) * surface
        beyond[ok] += dist >= surface
    return tuple((votes > 0) & (x > 0.5 * votes) for x in (front, back, beyond))
