"""Camera conventions of dataset formats and their conversion to Mitsuba's camera frame (+x left, +y up,
+z forward).

* OpenGL / Blender / nerfstudio ``transform_matrix``: camera-to-world, axes +x right, +y up, +z back.
* LLFF ``poses_bounds.npy``: 3x5 per view, rotation columns [down, right, back], then the camera
  position and [H, W, focal] of the original images.
"""
import numpy as np

from ..cameras import Camera

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
