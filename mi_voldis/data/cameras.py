"""Camera conventions and conversions to Mitsuba's camera frame (+x left, +y up, +z forward).

* OpenGL / Blender / nerfstudio ``transform_matrix``: camera-to-world, axes +x right, +y up, +z back.
* LLFF ``poses_bounds.npy``: 3x5 per view, rotation columns [down, right, back], then the camera
  position and [H, W, focal] of the original images.
"""
import numpy as np

from .types import Camera

GL_TO_MI = np.diag([-1.0, 1.0, -1.0, 1.0])  # flips x (right -> left) and z (back -> forward)


def opengl_to_mitsuba(c2w):
    """Mitsuba ``to_world`` of an OpenGL camera-to-world matrix (3x4 or 4x4)."""
    m = np.eye(4)
    m[:3, :4] = np.asarray(c2w, dtype=np.float64)[:3, :4]
    return m @ GL_TO_MI


def mitsuba_to_opengl(to_world):
    return np.asarray(to_world, dtype=np.float64) @ GL_TO_MI


def llff_to_mitsuba(pose):
    """Mitsuba ``to_world`` of an LLFF 3x5 pose: Mitsuba x = -right, y = -down, z = -back."""
    pose = np.asarray(pose, dtype=np.float64)
    down, right, back, position = pose[:, 0], pose[:, 1], pose[:, 2], pose[:, 3]
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = -right, -down, -back, position
    return m


def mitsuba_to_llff(to_world, height, width, focal):
    """LLFF 3x5 pose of a Mitsuba ``to_world`` (inverse of :func:`llff_to_mitsuba`)."""
    m = np.asarray(to_world, dtype=np.float64)
    pose = np.zeros((3, 5))
    pose[:, 0], pose[:, 1], pose[:, 2], pose[:, 3] = -m[:3, 1], -m[:3, 0], -m[:3, 2], m[:3, 3]
    pose[:, 4] = (height, width, focal)
    return pose


def fov_from_focal(focal, width):
    """Horizontal field of view (degrees) of a focal length in pixels."""
    return float(np.degrees(2 * np.arctan(0.5 * width / focal)))


def camera_from_intrinsics(to_world, width, height, fx, cx=None, cy=None):
    """Camera with OpenCV-style intrinsics (pixels; cx, cy default to the image centre)."""
    cx = 0.5 * width if cx is None else cx
    cy = 0.5 * height if cy is None else cy
    return Camera(np.asarray(to_world, np.float64), fov_from_focal(fx, width), int(width), int(height),
                  (0.5 - cx / width, 0.5 - cy / height))


def rigid_error(m):
    """How far the rotation part of ``m`` is from a proper rotation (max entry of R^T R - I, det)."""
    r = np.asarray(m, dtype=np.float64)[:3, :3]
    return max(np.abs(r.T @ r - np.eye(3)).max(), abs(np.linalg.det(r) - 1.0))


def pixel_rays(camera, px, py):
    """World rays through film positions (px, py) in pixels (pixel centres at +0.5), as Mitsuba's
    perspective sensor generates them. Returns origins (n, 3) and unit directions (n, 3)."""
    px, py = np.asarray(px, np.float64), np.asarray(py, np.float64)
    t = 2 * np.tan(np.radians(camera.fov_x) / 2)
    x = (0.5 - px / camera.width - camera.principal[0]) * t
    y = (0.5 - py / camera.height - camera.principal[1]) * t * camera.height / camera.width
    d = np.stack([x, y, np.ones_like(x)], axis=-1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    m = np.asarray(camera.to_world, np.float64)
    d_world = d @ m[:3, :3].T
    o = np.broadcast_to(m[:3, 3], d_world.shape)
    return o.copy(), d_world
