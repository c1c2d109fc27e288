"""Scene boxes from camera layouts: a world box for 360-degree captures, NDC for forward-facing ones."""
import numpy as np

from ..cameras import pixel_of, pixel_rays
from ..space import SceneBox, SceneSpace
from .types import DatasetError

NERF_NEAR = 1.0  # NeRF's NDC near plane (world units), used when nothing gives depth bounds
NEAR_FRACTION = 0.75  # forward-facing captures: rays start at 0.75 x the nearest depth bound (NeRF's NDC near plane)
SILHOUETTE_LATTICE = 64  # points along each side of the box that silhouette_box carves
SILHOUETTE_MARGIN = 2  # lattice cells the silhouette box grows by


def look_at_point(cameras):
    """Point closest (least squares) to every camera's optical axis."""
    a, b = np.zeros((3, 3)), np.zeros(3)
    for cam in cameras:
        m = np.asarray(cam.to_world)
        o, d = m[:3, 3], m[:3, 2] / np.linalg.norm(m[:3, 2])
        p = np.eye(3) - np.outer(d, d)
        a += p
        b += p @ o
    return np.linalg.lstsq(a, b, rcond=None)[0]


def rig_extent(cameras):
    """The rig's size (world units): the largest distance of a camera centre from their mean, the unit
    nerfstudio scales a capture's poses to (centred on their mean, the largest coordinate 1). An orbit's
    radius; a forward-facing rig's spread, small beside the depth of what it looks at."""
    pos = np.array([np.asarray(c.to_world)[:3, 3] for c in cameras])
    return float(np.max(np.linalg.norm(pos - pos.mean(axis=0), axis=1)))


def world_box(cameras, margin=1.1):
    """Cube around the cameras' common look-at point, sized so that it fills the narrowest view
    from the median camera distance (generous: fitting tightens it to occupied space)."""
    centre = look_at_point(cameras)
    dist = np.median([np.linalg.norm(np.asarray(c.to_world)[:3, 3] - centre) for c in cameras])
    fov = min(min(c.fov_x, 2 * np.degrees(np.arctan(np.tan(np.radians(c.fov_x) / 2) * c.height / c.width)))
              for c in cameras)
    half = margin * dist * np.tan(np.radians(fov) / 2)
    return SceneBox("world", centre - half, centre + half)


def silhouette_box(cameras, alphas, box, lattice=SILHOUETTE_LATTICE):
    """World box of what views with an alpha channel show (an object rendered on an empty backdrop,
    Blender's RGBA layout): the box of the visual hull their ``alphas`` (per camera (H, W) in [0, 1])
    carve out of ``box`` (the camera layout's generous box), on ``lattice``^3 points: a point stays
    where every view that has it in frame covers it (alpha > 0; views it falls outside of abstain), and
    the box of those grows by SILHOUETTE_MARGIN lattice cells (a part thinner than a cell can fall
    between the points). The hull holds the object (each view's silhouette does), so nothing seen is
    cut off. None where no point stays (poses and
    alphas that disagree) or the hull reaches a face of ``box`` (the object may go on beyond it)."""
    axes = [np.linspace(a, b, lattice) for a, b in zip(box.lo, box.hi)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    keep, seen = np.ones(len(points), bool), np.zeros(len(points), bool)
    for cam, alpha in zip(cameras, alphas):
        ix, iy, inside = pixel_of(cam, points)
        covered = np.zeros(len(points), bool)
        covered[inside] = alpha[iy[inside], ix[inside]] > 0
        keep &= covered | ~inside
        seen |= inside
    keep &= seen
    if not keep.any():
        return None
    index = np.stack(np.unravel_index(np.flatnonzero(keep), (lattice,) * 3), -1)
    if index.min() == 0 or index.max() == lattice - 1:
        return None
    cell = (np.asarray(box.hi) - np.asarray(box.lo)) / (lattice - 1)
    grow = SILHOUETTE_MARGIN * cell
    return SceneBox("world", points[keep].min(axis=0) - grow, points[keep].max(axis=0) + grow)


def is_forward_facing(cameras):
    """All cameras look the same way (within ~25 degrees of their mean) from a compact cluster."""
    fwd = np.array([np.asarray(c.to_world)[:3, 2] for c in cameras])
    fwd /= np.linalg.norm(fwd, axis=1, keepdims=True)
    mean = fwd.mean(axis=0)
    mean /= np.linalg.norm(mean)
    return bool(np.min(fwd @ mean) > np.cos(np.radians(25)))


def average_pose(cameras):
    """Mitsuba-frame camera at the mean position, looking along the mean forward direction."""
    m = np.array([np.asarray(c.to_world) for c in cameras])
    forward = m[:, :3, 2].mean(axis=0)
    forward /= np.linalg.norm(forward)
    up = m[:, :3, 1].mean(axis=0)
    left = np.cross(up, forward)
    left /= np.linalg.norm(left)
    up = np.cross(forward, left)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = left, up, forward, m[:, :3, 3].mean(axis=0)
    return pose


def capture_box(cameras, points, where, notes, forward=None, near=None, far=None, aabb=None):
    """(scene box, near/far bounds or None) of a capture. Forward-facing (``forward``, else detected):
    NDC with the given bounds, else the sparse ``points``' (:func:`~mi_voldis.data.points.depth_bounds`),
    else NeRF's default near plane, a line in ``notes`` saying which. Otherwise ``aabb`` when stated,
    else the points' box (with the cameras), else a box from the camera layout."""
    from .points import depth_bounds, points_box
    if forward is None:
        forward = is_forward_facing(cameras)
    if forward:
        if not (near and far):
            bounds = [b for b in depth_bounds(cameras, points) if b is not None] if points is not None else []
            if bounds:
                near, far = float(min(b[0] for b in bounds)), float(max(b[1] for b in bounds))
                notes.append(f"{where}: no near/far given; from the sparse points: near {near:.4g}, far {far:.4g}")
            else:
                near, far = NERF_NEAR, 1e3 * NERF_NEAR
                notes.append(f"{where}: no near/far and no points; NeRF's default near plane {near:g} (far {far:g})")
        if not 0 < near < far:
            raise DatasetError(f"{where}: near ({near}) and far ({far}) must satisfy 0 < near < far")
        return ndc_box(cameras, near, far), np.array([[near, far]])
    if aabb is not None:
        return SceneBox("world", aabb[0], aabb[1]), None
    if points is not None and len(points) >= 10:
        lo, hi = points_box(points)
        pos = np.array([np.asarray(c.to_world)[:3, 3] for c in cameras])
        return SceneBox("world", np.minimum(lo, pos.min(axis=0)), np.maximum(hi, pos.max(axis=0))), None
    return world_box(cameras), None


def ndc_box(cameras, near, far, z_max=0.999):
    """NDC scene box of forward-facing cameras (NeRF's LLFF convention: the reference camera is the
    average pose, near = the given near plane). The x', y' extent covers every view's frustum from
    ``near`` to ``far``; z' runs from the near plane (-1) to ``z_max`` (1 is infinity)."""
    ref = average_pose(cameras)
    cam = cameras[0]
    scale = (2 * cam.focal / cam.width, 2 * cam.focal / cam.height)
    space = SceneSpace("ndc", ref, near, scale)
    pts = []
    for c in cameras:
        px = np.array([0, c.width, 0, c.width, 0.5 * c.width])
        py = np.array([0, 0, c.height, c.height, 0.5 * c.height])
        o, d = pixel_rays(c, px, py)
        for depth in np.geomspace(near, far, 8):
            pts.append(o + depth * d)
    pts = np.concatenate(pts)
    in_front = (pts - ref[:3, 3]) @ ref[:3, 2] > 0.5 * near
    ndc = space.from_world_np(pts[in_front])
    lo, hi = ndc.min(axis=0), ndc.max(axis=0)
    pad = 0.05 * (hi - lo)
    lo[:2], hi[:2] = lo[:2] - pad[:2], hi[:2] + pad[:2]
    lo[2], hi[2] = -1.0, z_max
    return SceneBox("ndc", lo, hi, ref, near, scale)


def contracted_box(cameras, forward_facing, near=None, shell=1.0, radius_scale=1.0):
    """Contracted space of a capture (:mod:`mi_voldis.space`): the inner cube holds every camera.

    360-degree captures: centred on the cameras' common look-at point, axis-aligned, half-size
    ``radius_scale`` x 1.1 x the farthest camera's distance from it, so that (at 1) the object and the
    cameras' ring stay linear and the far background fills the shell. Forward-facing captures: centred
    on the cameras, in the frame of their average pose, half-size the larger of 1.1 x the rig's radius
    and half the nearest depth ``near``: the scene lies in the shell, uniform in disparity as in NDC,
    and views from off the rig still see it."""
    positions = np.array([np.asarray(c.to_world)[:3, 3] for c in cameras])
    if forward_facing:
        frame = average_pose(cameras)
        centre = positions.mean(axis=0)
        radius = 1.1 * np.max(np.linalg.norm(positions - centre, axis=1))
        if near is not None:
            radius = max(radius, 0.5 * float(near))
    else:
        frame = np.eye(4)
        centre = look_at_point(cameras)
        radius = radius_scale * 1.1 * np.max(np.linalg.norm(positions - centre, axis=1))
    to_world = frame.copy()
    to_world[:3, :3] = frame[:3, :3] * radius
    to_world[:3, 3] = centre
    e = 1.0 + shell
    start = NEAR_FRACTION * float(near) if forward_facing and near is not None else 0.0
    return SceneBox("contract", np.full(3, -e), np.full(3, e), to_world=to_world, shell=shell, near=start)


def fitting_box(dataset, space="auto", shell=1.0, radius_scale=1.0):
    """The scene box a fit uses: the dataset's own box for 'world' or 'ndc' (a bounded scene states its
    box; forward-facing loaders give NDC), a contracted space for 'contract'; 'auto' keeps a world box
    that is stated (``meta['aabb']``) or carved from the views' alpha (``meta['silhouette_box']``: an
    object on an empty backdrop) and contracts everything else, forward-facing captures included: on the
    CPU fern and the statue fitted better contracted than in NDC under the default plan (reports/notes.md)."""
    box = dataset.box
    if space == "auto":
        bounded = dataset.meta.get("aabb") or dataset.meta.get("silhouette_box")
        space = "world" if box.kind == "world" and bounded else "contract"
    if space == box.kind:
        return box
    if space == "contract":
        near = float(np.min(dataset.near_far)) if dataset.near_far is not None else None
        return contracted_box(dataset.cameras, box.kind == "ndc" or is_forward_facing(dataset.cameras), near, shell,
                              radius_scale)
    raise ValueError(f"{dataset.root}: a '{space}' scene space needs a dataset that gives one (it gives "
                     f"'{box.kind}')")
