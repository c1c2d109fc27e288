"""Scene boxes from camera layouts: a world box for 360-degree captures, NDC for forward-facing ones."""
import numpy as np

from ..cameras import pixel_rays
from ..space import SceneBox, SceneSpace


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


def world_box(cameras, margin=1.1):
    """Cube around the cameras' common look-at point, sized so that it fills the narrowest view
    from the median camera distance (generous: fitting tightens it to occupied space)."""
    centre = look_at_point(cameras)
    dist = np.median([np.linalg.norm(np.asarray(c.to_world)[:3, 3] - centre) for c in cameras])
    fov = min(min(c.fov_x, 2 * np.degrees(np.arctan(np.tan(np.radians(c.fov_x) / 2) * c.height / c.width)))
              for c in cameras)
    half = margin * dist * np.tan(np.radians(fov) / 2)
    return SceneBox("world", centre - half, centre + half)


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
