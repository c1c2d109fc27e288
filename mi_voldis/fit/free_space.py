"""The space the object masks prove empty, kept empty while the full field is fitted.

A training pixel inside the object's mask shows the object: occluders in front of it are outside the mask
(:mod:`mi_voldis.fit.hull`), so along that pixel's ray nothing stands between the camera and the object.
The object lies in its visual hull H (the masks' cones intersected, grown by ``hull_dilation``); so a point
p outside H whose pixel in view j lies inside mask j, nearer to camera j than H is on that pixel,

    p not in H,  pi_j(p) in erode(M_j),  |p - c_j| < (1 - m) min { |q - c_j| : q in H, pi_j(q) ~ pi_j(p) },

is empty space, m a margin (``free_space_margin``). Left free, a fit can draw the object on a veil in front
of it that each training view sees at its own place (a painted screen; the photographs are reproduced,
off-path views and the geometry are not), and the background keeps that veil: the removed object's
glassy ghost. ``q ~ p``: the hull's vertices projected into the pixel or its neighbours within the footprint
of a voxel; a pixel with none around is left alone, so what lies behind the object is never taken.

A vertex's density reaches every point of the eight cells around it (trilinear interpolation), a cube of
half-side one voxel v whose image is a disc of radius up to sqrt(3) v / (|p - c_j| a) pixels (a: a pixel's
angle). Where an occluder stands in front of the object its gap in the mask is narrow (a pole: a few pixels):
the vertices about the occluder project inside the mask though their cells draw its edges. So p must lie
farther than that radius from every gap, the pixels a closing of M_j adds (gaps up to a few voxels wide at
the hull's distance): the occluder keeps its edges. At the mask's outer edge the rays beside it pass the
same empty space, so there the eroded mask alone decides.

A closing also fills the notches between the object's parts (a box beside a ball), whose rays pass the
object and meet the background behind it. Once the full field is fitted (each lattice after the first),
a gap pixel counts only where its ray gathers an opacity of ``OCCLUDER_OPACITY`` before the hull on that
pixel: an occluder. Behind the hull, or nowhere, it is a notch, and the space about it stays free.
"""
import cv2
import drjit as dr
import mitsuba as mi
import numpy as np

from ..cameras import DevicePoints, device_image, pixel_rays
from ..data.types import spread
from ..field.state import vertex_positions
from ..metrics import diagonal_pixels
from ..render.surface import median_points
from .hull import visual_hull

VIEWS = 24  # masked training views spread over the set that mark the free space (each a pass over the vertices)
GAP_VOXELS = 2  # gaps in a mask narrower than about 4 voxels' image at the hull's distance are occluders' (a pole)
OCCLUDER_OPACITY = 0.25  # a gap's ray that gathers this much opacity before the hull meets an occluder


def nearest_filter(image, radius):
    """The minimum of ``image`` (H, W) over each pixel's (2 radius + 1)^2 neighbourhood (inf beyond the edge)."""
    square = np.ones((2 * radius + 1, 2 * radius + 1), np.uint8)
    return cv2.erode(np.asarray(image, np.float64), square, borderType=cv2.BORDER_CONSTANT, borderValue=np.inf)


def free_vertices(field, space, cameras, masks, dilation_px, min_fraction, margin, gap_depth=None):
    """Bool per stored vertex of ``field`` (NumPy): in the free space the masks prove (module docstring), by
    ``cameras`` and their ``masks`` ((N, H, W) bool); the hull from the masks grown by ``dilation_px`` in
    ``min_fraction`` of the views that see a point (:func:`~mi_voldis.fit.hull.visual_hull`).
    ``gap_depth(camera, pixels)``, where given: the distance along each of the flat ``pixels``' rays at which
    something stands (inf where nothing does): a gap counts only where that lies before the hull. Each view's
    rule is made an image (how near a vertex must be, how far the gaps are) and asked of every vertex in one
    kernel (:class:`~mi_voldis.cameras.DevicePoints`); only the hull's vertices come back to the host."""
    pts, real = vertex_positions(field)
    out = np.zeros(len(pts), bool)
    pick = np.flatnonzero(real)
    if not len(pick) or not len(cameras):
        return out
    world = space.to_world_np(pts[pick])
    hull = visual_hull(world, cameras, masks, dilation_px, min_fraction)
    if not hull.any():
        return out
    voxel = float(np.max(np.diag(field.to_world)[:3] / (np.array(field.shape) - 1)))
    at, shell = DevicePoints(world), DevicePoints(world[hull])
    free = dr.zeros(mi.Bool, at.count)
    for cam, mask in zip(cameras, masks):
        index, ok = (np.array(a) for a in shell.pixel_of(cam))
        ok = ok.astype(bool)
        if not ok.any():
            continue
        dist = np.array(shell.distance(cam))[ok]
        near = np.full(mask.size, np.inf)
        np.minimum.at(near, index[ok], dist)
        angle = np.radians(cam.fov_x) / cam.width  # a pixel's angle
        # space lattices (contracted, NDC) stretch voxels in world space: read their size where the hull is
        edge = voxel_world(space, world[hull][ok], voxel)
        # a voxel of the hull spans this many pixels at the hull's distance, plus one for the vertex's
        # rounding: that far its nearest distance reaches
        radius = int(np.ceil(edge / (angle * float(np.median(dist))))) + 1
        ahead = nearest_filter(near.reshape(mask.shape), radius)
        inner = inside_depth(mask) > 1.5  # the mask eroded by a pixel: its edge mixes
        # free nearer than this: 0 (none) off the eroded mask and where no hull lies ahead
        limit = np.where(inner & np.isfinite(ahead), (1.0 - margin) * ahead, 0.0)
        gaps = mask_gaps(mask, GAP_VOXELS * radius)
        if gap_depth is not None and gaps.any():  # an occluder's gaps alone: its surface lies before the hull
            at_gap = np.flatnonzero(gaps)
            hull_at = ahead.reshape(-1)[at_gap]
            hull_at = np.where(np.isfinite(hull_at), hull_at, dist.min())
            gaps.flat[at_gap] = gap_depth(cam, at_gap) < hull_at
        gaps = distance_to(gaps)
        index, ok = at.pixel_of(cam)
        d = at.distance(cam)
        ahead_ok = d < dr.gather(mi.Float64, device_image(limit, mi.Float64), index, ok)
        # the vertex's reach in pixels (module docstring), plus one: its pixel's edge mixes the two sides (the
        # view's numbers opaque: one kernel serves every view)
        reach = dr.opaque(mi.Float64, np.sqrt(3.0) * edge / angle) / dr.maximum(d, 1e-12) + 1.0
        clear = dr.gather(mi.Float64, device_image(gaps, mi.Float64), index, ok) > reach
        free |= ok & ahead_ok & clear
        dr.eval(free)
    out[pick[free.numpy().astype(bool) & ~hull]] = True
    return out


def inside_depth(mask):
    """Each pixel's distance (pixels) to the nearest pixel outside ``mask`` (H, W) or outside the image; 0
    outside the mask."""
    padded = np.pad(np.asarray(mask, np.uint8), 1)  # beyond the image nothing is known to be the object
    return cv2.distanceTransform(padded, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)[1:-1, 1:-1]


def mask_gaps(mask, width):
    """The gaps of ``mask`` (H, W): the pixels outside it that a closing by a (2 ``width`` + 1)^2 square
    fills, strips up to about 2 ``width`` pixels across with the mask on both sides (H, W) bool."""
    m = np.pad(np.asarray(mask, np.uint8), width + 1)  # beyond the image: not the mask, so no gap at its edge
    closed = cv2.morphologyEx(m, cv2.MORPH_CLOSE, np.ones((2 * width + 1, 2 * width + 1), np.uint8))
    return ((closed > 0) & (m == 0))[width + 1:-width - 1, width + 1:-width - 1]


def distance_to(pixels):
    """Each pixel's distance (pixels) to the nearest of ``pixels`` (H, W) bool (inf where there is none)."""
    if not pixels.any():
        return np.full(pixels.shape, np.inf)
    return cv2.distanceTransform((~pixels).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)


def voxel_world(space, world, voxel):
    """The world length of a scene-space voxel of edge ``voxel`` at the median of the points ``world``."""
    centre = np.median(world, axis=0)
    ends = space.from_world_np(np.stack([centre, centre]))
    ends[1] = ends[1] + voxel / np.sqrt(3.0)
    back = space.to_world_np(ends)
    return float(max(np.linalg.norm(back[1] - back[0]), 1e-12))


def field_gap_depth(integrator):
    """``gap_depth`` for :func:`free_vertices` from the full field of ``integrator``: the distance along each
    pixel's ray at which its opacity reaches :data:`OCCLUDER_OPACITY` (inf where it never does)."""
    def depth(camera, pixels):
        o, d = pixel_rays(camera, pixels % camera.width + 0.5, pixels // camera.width + 0.5)
        points, hit = median_points(integrator, o, d, level=1.0 - OCCLUDER_OPACITY)
        return np.where(hit, np.linalg.norm(points - o, axis=1), np.inf)
    return depth


def training_free_space(inputs, field, integrator=None):
    """:func:`free_vertices` of ``field`` from up to :data:`VIEWS` of the masked training views of ``inputs``
    (None without masks or without ``free_space``); ``integrator``: a fit of the full field, whose surfaces
    tell the masks' gaps that an occluder makes (:func:`field_gap_depth`)."""
    cfg, ds = inputs.cfg, inputs.ds
    if not cfg.free_space or ds.masks is None or not len(ds.masked_train):
        return None
    views = [ds.masked_train[k] for k in spread(len(ds.masked_train), VIEWS)]
    return free_vertices(field, inputs.space, [ds.cameras[v] for v in views], ds.masks[views],
                         diagonal_pixels(cfg.hull_dilation, ds.size), cfg.hull_min_views, cfg.free_space_margin,
                         None if integrator is None else field_gap_depth(integrator))
