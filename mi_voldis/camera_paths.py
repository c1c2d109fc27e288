"""Camera paths for videos: an orbit, a spiral, an interpolation through a capture's views, and
nerfstudio's ``camera_path.json``. Every path is a list of :class:`~mi_voldis.cameras.Camera` with the
capture's field of view and image size unless given.

* ``orbit``: around the point nearest every optical axis (:func:`~mi_voldis.data.scene_box.
  look_at_point`), at the cameras' median distance and mean height above it along their mean up
  direction, looking at it: a turntable for 360-degree captures.
* ``spiral``: NeRF's forward-facing path: about the average pose, an ellipse in its image plane of
  the rig's extent (90th percentile of the cameras' offsets) that also moves along the view, all
  looking at a point ahead (:func:`focus_depth`).
* ``interpolate``: through the capture's views in order (positions linearly, rotations by
  spherical linear interpolation of quaternions).
* nerfstudio ``camera_path.json``: ``camera_path[k].camera_to_world`` (16 numbers, row-major, OpenGL
  axes), ``fov`` (vertical, degrees), ``render_width`` / ``render_height``; nerfstudio's viewer works in
  its dataparser's frame, so ``dataparser_transforms.json`` (``transform`` 3x4, ``scale``) maps it back
  to the capture's world when given: x_viewer = scale * (T x).
"""
import json

import numpy as np

from .cameras import Camera, look_at
from .data.conventions import opengl_to_mitsuba
from .data.scene_box import average_pose, look_at_point
from .transforms import quaternion_to_rotation, rotation_to_quaternion

PATHS = ("orbit", "spiral", "interpolate")


def _like(camera, to_world):
    return Camera(to_world, camera.fov_x, camera.width, camera.height, camera.principal)


def orbit(cameras, frames):
    target = look_at_point(cameras)
    up = np.mean([np.asarray(c.to_world)[:3, 1] for c in cameras], axis=0)
    up /= np.linalg.norm(up)
    offsets = np.array([np.asarray(c.to_world)[:3, 3] - target for c in cameras])
    height = float(np.mean(offsets @ up))
    flat = offsets - np.outer(offsets @ up, up)
    radius = float(np.median(np.linalg.norm(flat, axis=1)))
    e1 = flat[0] / np.linalg.norm(flat[0])
    e2 = np.cross(up, e1)
    out = []
    for k in range(frames):
        a = 2 * np.pi * k / frames
        pos = target + height * up + radius * (np.cos(a) * e1 + np.sin(a) * e2)
        out.append(_like(cameras[0], look_at(pos, target, up)))
    return out


def focus_depth(cameras, near_far=None):
    """How far ahead of the average pose the spiral looks: NeRF's 1 / (0.25 / near + 0.75 / far) with
    depth bounds, else the distance to the point nearest every optical axis when it lies ahead, else
    ten times the rig's radius."""
    if near_far is not None:
        near, far = float(np.min(near_far)), float(np.max(near_far))
        return 1.0 / (0.25 / near + 0.75 / far)
    ref = average_pose(cameras)
    ahead = float((look_at_point(cameras) - ref[:3, 3]) @ ref[:3, 2])
    if ahead > 0:
        return ahead
    pos = np.array([np.asarray(c.to_world)[:3, 3] for c in cameras])
    return 10.0 * max(float(np.max(np.linalg.norm(pos - pos.mean(axis=0), axis=1))), 1e-3)


def spiral(cameras, frames, near_far=None, rotations=2):
    ref = average_pose(cameras)
    centre, left, up, forward = ref[:3, 3], ref[:3, 0], ref[:3, 1], ref[:3, 2]
    offsets = np.array([np.asarray(c.to_world)[:3, 3] - centre for c in cameras])
    rx = max(float(np.percentile(np.abs(offsets @ left), 90)), 1e-3)
    ry = max(float(np.percentile(np.abs(offsets @ up), 90)), 1e-3)
    focus = centre + forward * focus_depth(cameras, near_far)
    out = []
    for k in range(frames):
        a = 2 * np.pi * rotations * k / frames
        pos = centre + rx * np.cos(a) * left + ry * np.sin(a) * up + 0.5 * min(rx, ry) * np.sin(a / rotations) * forward
        out.append(_like(cameras[0], look_at(pos, focus, up)))
    return out


def slerp(q0, q1, t):
    """Spherical linear interpolation of unit quaternions (the shorter arc)."""
    d = float(np.dot(q0, q1))
    if d < 0:
        q1, d = -q1, -d
    if d > 0.9995:
        q = q0 + t * (q1 - q0)
        return q / np.linalg.norm(q)
    theta = np.arccos(d)
    return (np.sin((1 - t) * theta) * q0 + np.sin(t * theta) * q1) / np.sin(theta)


def interpolate(cameras, frames):
    """``frames`` cameras through ``cameras`` in order, evenly in the path's parameter."""
    m = [np.asarray(c.to_world, np.float64) for c in cameras]
    if len(m) == 1:
        return [_like(cameras[0], m[0]) for _ in range(frames)]
    out = []
    for k in range(frames):
        s = k * (len(m) - 1) / max(frames - 1, 1)
        i = min(int(s), len(m) - 2)
        t = s - i
        pose = np.eye(4)
        pose[:3, :3] = quaternion_to_rotation(slerp(rotation_to_quaternion(m[i][:3, :3]),
                                                            rotation_to_quaternion(m[i + 1][:3, :3]), t))
        pose[:3, 3] = (1 - t) * m[i][:3, 3] + t * m[i + 1][:3, 3]
        out.append(_like(cameras[i], pose))
    return out


def make_path(kind, cameras, frames, near_far=None):
    """The path ``kind`` of ``frames`` cameras from a capture's ``cameras`` (``near_far``: its depth
    bounds, for the spiral's focus)."""
    if kind not in PATHS:
        raise ValueError(f"unknown camera path '{kind}' (expected {', '.join(PATHS)} or a camera_path.json)")
    if frames < 1:
        raise ValueError(f"a camera path needs at least one frame, got {frames}")
    if kind == "spiral":
        return spiral(cameras, frames, near_far)
    return {"orbit": orbit, "interpolate": interpolate}[kind](cameras, frames)


def read_nerfstudio_path(path, dataparser=None):
    """Cameras of a nerfstudio ``camera_path.json`` (see the module docstring)."""
    try:
        with open(path) as f:
            data = json.load(f)
        width, height = int(data["render_width"]), int(data["render_height"])
        entries = data["camera_path"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise ValueError(f"{path}: not a nerfstudio camera path ({type(e).__name__}: {e})") from None
    back = np.eye(4)
    if dataparser is not None:
        try:
            with open(dataparser) as f:
                dp = json.load(f)
            t = np.eye(4)
            t[:3, :4] = np.asarray(dp["transform"], np.float64)[:3, :4]
            scale = float(dp["scale"])
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise ValueError(f"{dataparser}: not a dataparser_transforms.json ({type(e).__name__}: {e})") from None
        back = np.linalg.inv(t) @ np.diag([1 / scale, 1 / scale, 1 / scale, 1.0])
    out = []
    for k, entry in enumerate(entries):
        try:
            c2w = np.asarray(entry["camera_to_world"], np.float64).reshape(4, 4)
            fov_y = float(entry["fov"])
        except (KeyError, ValueError, TypeError) as e:
            raise ValueError(f"{path}: camera_path[{k}] is malformed ({type(e).__name__}: {e})") from None
        c2w = back @ c2w
        c2w[:3, :3] /= np.linalg.norm(c2w[:3, :3], axis=0)  # the viewer's scale is not the camera's
        fov_x = np.degrees(2 * np.arctan(np.tan(np.radians(fov_y) / 2) * width / height))
        out.append(Camera(opengl_to_mitsuba(c2w), float(fov_x), width, height))
    if not out:
        raise ValueError(f"{path}: the camera path is empty")
    return out
