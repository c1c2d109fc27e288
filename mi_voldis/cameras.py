"""Pinhole cameras in Mitsuba's convention: the camera type, rays through pixels, and the projection of
world points to pixels. A leaf module: datasets, rendering, fitting and tasks all import it.

The pinhole model, written once (:func:`film_to_camera` and its inverse :func:`camera_to_film`): a
film position (u, v) in [0, 1]^2 (u = px / W, v = py / H, pixel centres at +0.5) has the camera-frame
direction

    x = (0.5 - u - o_x) tan_x,   y = (0.5 - v - o_y) tan_y,   z = 1,

with tan_x = 2 tan(fov_x / 2), tan_y = tan_x H / W and (o_x, o_y) Mitsuba's principal point offsets;
Mitsuba's camera frame has +x left, +y up, +z forward. The functions take NumPy or Dr.Jit arrays.
"""
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from .transforms import to_scalar_transform


@dataclass
class Camera:
    """A pinhole camera in Mitsuba's convention.

    ``to_world``: rigid 4x4 camera-to-world matrix whose axes are Mitsuba's camera frame (+x left,
    +y up, +z forward); ``fov_x``: horizontal field of view in degrees; ``principal``: Mitsuba's
    ``principal_point_offset_x/y`` (principal point = film centre minus ``principal`` times the film
    size; OpenCV's cx = W (0.5 - principal_x), cy = H (0.5 - principal_y))."""
    to_world: np.ndarray
    fov_x: float
    width: int
    height: int
    principal: tuple = (0.0, 0.0)

    @property
    def focal(self):
        """Focal length in pixels."""
        return 0.5 * self.width / np.tan(np.radians(self.fov_x) / 2)

    @property
    def tan_scale(self):
        """(tan_x, tan_y): camera-frame extent of the film at unit depth."""
        t = 2 * np.tan(np.radians(self.fov_x) / 2)
        return t, t * self.height / self.width

    def sensor_dict(self, spp=1, near_clip=1e-4):
        """Plugin dict of the equivalent Mitsuba ``perspective`` sensor with a box-filtered RGB film."""
        return {"type": "perspective", "fov": float(self.fov_x), "fov_axis": "x", "near_clip": near_clip,
                "principal_point_offset_x": float(self.principal[0]),
                "principal_point_offset_y": float(self.principal[1]),
                "to_world": to_scalar_transform(self.to_world),
                "film": {"type": "hdrfilm", "width": int(self.width), "height": int(self.height),
                         "pixel_format": "rgb", "rfilter": {"type": "box"}},
                "sampler": {"type": "independent", "sample_count": spp}}


def look_at(origin, target, up=(0.0, 1.0, 0.0)):
    """Mitsuba-frame camera-to-world matrix (+x left, +y up, +z forward) looking from origin at target."""
    origin, target, up = (np.asarray(v, np.float64) for v in (origin, target, up))
    forward = target - origin
    forward /= np.linalg.norm(forward)
    left = np.cross(up, forward)
    left /= np.linalg.norm(left)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = left, np.cross(forward, left), forward, origin
    return m


def world_up(cameras, spread=0.1):
    """The world's up as the cameras suggest it (unit 3-vector). Cameras held level have horizontal
    +x axes, so up is the direction orthogonal to all of them: the eigenvector of sum x x^T with the
    least eigenvalue, signed as the mean camera +y. Where the +x axes barely turn (a forward-facing
    rig: the middle eigenvalue below ``spread`` times the largest) that direction is not determined,
    and up is the mean +y made orthogonal to the mean +x: the rig's own up, pitched as the rig is."""
    frames = np.stack([np.asarray(c.to_world, np.float64)[:3, :3] for c in cameras])
    x, y = frames[:, :, 0], frames[:, :, 1]
    mean_y = y.mean(0)
    values, vectors = np.linalg.eigh(x.T @ x)  # ascending
    if values[1] >= spread * values[2]:
        up = vectors[:, 0]
    else:
        mean_x = x.mean(0) / np.linalg.norm(x.mean(0))
        up = mean_y - np.dot(mean_y, mean_x) * mean_x
    up = up / np.linalg.norm(up)
    return up if np.dot(up, mean_y) >= 0 else -up


def film_to_camera(u, v, tan_x, tan_y, offset_x, offset_y):
    """Camera-frame direction (x, y, 1) through film position (u, v) (see the module docstring)."""
    return (0.5 - u - offset_x) * tan_x, (0.5 - v - offset_y) * tan_y


def camera_to_film(x, y, z, tan_x, tan_y, offset_x, offset_y):
    """Film position (u, v) of the camera-frame point (x, y, z), z > 0: the inverse of
    :func:`film_to_camera`."""
    return 0.5 - offset_x - x / (z * tan_x), 0.5 - offset_y - y / (z * tan_y)


def pixel_rays(camera, px, py):
    """World rays through film positions (px, py) in pixels (pixel centres at +0.5), as Mitsuba's
    perspective sensor generates them. Returns origins (n, 3) and unit directions (n, 3), NumPy."""
    px, py = np.asarray(px, np.float64), np.asarray(py, np.float64)
    x, y = film_to_camera(px / camera.width, py / camera.height, *camera.tan_scale, *camera.principal)
    d = np.stack([x, y, np.ones_like(x)], axis=-1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    m = np.asarray(camera.to_world, np.float64)
    d_world = d @ m[:3, :3].T
    return np.broadcast_to(m[:3, 3], d_world.shape).copy(), d_world


def project(camera, points):
    """Pixel coordinates (px, py) and camera-frame depth z of world points (n, 3) (NumPy; px, py are
    meaningless where z <= 0)."""
    inv = np.linalg.inv(np.asarray(camera.to_world, np.float64))
    pc = np.asarray(points, np.float64) @ inv[:3, :3].T + inv[:3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        u, v = camera_to_film(pc[:, 0], pc[:, 1], pc[:, 2], *camera.tan_scale, *camera.principal)
    return camera.width * u, camera.height * v, pc[:, 2]


def pixel_of(camera, points):
    """Integer pixel (ix, iy) of world points (n, 3) and whether it lies in the frame, in front of the
    camera (ix, iy are meaningless where it does not)."""
    px, py, z = project(camera, points)
    ix, iy = np.floor(px).astype(np.int64), np.floor(py).astype(np.int64)
    return ix, iy, (z > 0) & (ix >= 0) & (ix < camera.width) & (iy >= 0) & (iy < camera.height)


class DevicePoints:
    """World points (n, 3) held on the device, for tests that ask every view about every point (the
    visual hull, what views see): each view's projection, gathers from its images and the sums run as
    Dr.Jit kernels (on the GPU with a CUDA variant), in float64 as :func:`project` computes, the view's
    numbers passed as opaque values so that one kernel serves every view."""

    def __init__(self, points):
        from .device import from_numpy
        self.count = len(points)
        self.points = from_numpy(mi.Point3d, np.asarray(points, np.float64).reshape(-1, 3))

    def pixel_of(self, camera):
        """Flat pixel index (y width + x, UInt32) of each point in ``camera`` and whether it lies in the
        frame, in front of the camera (Bool; the index is 0 where it does not): :func:`pixel_of`."""
        inv = np.linalg.inv(np.asarray(camera.to_world, np.float64))
        m = [dr.opaque(mi.Float64, float(v)) for v in inv[:3, :4].ravel()]
        p = self.points
        x, y, z = (m[4 * r] * p.x + m[4 * r + 1] * p.y + m[4 * r + 2] * p.z + m[4 * r + 3] for r in range(3))
        tx, ty, ox, oy = (dr.opaque(mi.Float64, float(v)) for v in (*camera.tan_scale, *camera.principal))
        u, v = camera_to_film(x, y, z, tx, ty, ox, oy)
        w, h = dr.opaque(mi.Float64, float(camera.width)), dr.opaque(mi.Float64, float(camera.height))
        fx, fy = dr.floor(w * u), dr.floor(h * v)
        ok = (z > 0) & (fx >= 0) & (fx < w) & (fy >= 0) & (fy < h)
        return dr.select(ok, mi.UInt32(mi.Int32(fy)) * camera.width + mi.UInt32(mi.Int32(fx)), 0), ok

    def distance(self, camera):
        """Distance (Float64) of each point from ``camera``'s centre."""
        o = np.asarray(camera.to_world, np.float64)[:3, 3]
        return dr.norm(self.points - mi.Point3d(*(dr.opaque(mi.Float64, float(v)) for v in o)))


def device_image(values, cls):
    """An image (H, W) or (H, W, C) as a flat Dr.Jit array of ``cls`` (``mi.Bool``, ``mi.Float64``),
    pixel y W + x at index (y W + x) C + c: what :meth:`DevicePoints.pixel_of`'s indices gather."""
    from .device import from_numpy
    return from_numpy(cls, np.asarray(values).reshape(-1))


TABLE_WIDTH = 16  # floats per camera in a CameraTable: rotation (9), origin (3), tan_x, tan_y, offsets (2)


class CameraTable:
    """Cameras of one image size on the device, for rays of many views in one kernel (fitting)."""

    def __init__(self, cameras):
        rows = []
        for c in cameras:
            m = np.asarray(c.to_world, np.float64)
            rows.append(np.concatenate([m[:3, :3].ravel(), m[:3, 3], c.tan_scale, c.principal]))
        self.cameras = list(cameras)
        self.data = mi.Float(np.asarray(rows, np.float32).ravel())

    def rays(self, view, u, v):
        """World rays (o, d) of camera ``view`` (UInt32 per ray) through film positions (u, v) (Float)."""
        cam = dr.gather(mi.ArrayXf, self.data, view, shape=(TABLE_WIDTH, dr.width(view)))
        x, y = film_to_camera(u, v, cam[12], cam[13], cam[14], cam[15])
        d = dr.normalize(mi.Vector3f(cam[0] * x + cam[1] * y + cam[2], cam[3] * x + cam[4] * y + cam[5],
                                     cam[6] * x + cam[7] * y + cam[8]))
        return mi.Point3f(cam[9], cam[10], cam[11]), d
