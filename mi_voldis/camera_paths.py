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
  axes), ``fov`` (vertical, degrees), ``render_width`` / ``render_height``, ``seconds`` (the video's
  length: frames / seconds is its frame rate, :func:`nerfstudio_fps`); ``camera_type`` perspective
  (or absent; others are refused). nerfstudio's viewer works in its dataparser's frame: it orients
  (O) and scales (s) the poses of ``transforms.json``, x_ns = s O x_json, and writes
  ``dataparser_transforms.json`` with ``transform`` T = O A and ``scale`` S = s a, where A and a are
  the capture's ``applied_transform`` and ``applied_scale`` (from the original data to
  ``transforms.json``; nerfstudio's default A for a capture with ``colmap/sparse/0`` and none stated).
  With both files, x_json = A T^-1 (a x_ns / S): where nerfstudio puts the camera in the capture's
  world.
"""
import json
import os

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


# nerfstudio's applied_transform for COLMAP captures converted before the field existed
# (nerfstudio_dataparser.py)
COLMAP_APPLIED = [[0, 1, 0, 0], [1, 0, 0, 0], [0, 0, -1, 0]]


def _read_json(path, what):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        raise ValueError(f"{path}: not {what} ({type(e).__name__}: {e})") from None


def capture_applied(capture):
    """(A 4x4, a): ``applied_transform`` and ``applied_scale`` of the capture folder ``capture``'s
    ``transforms.json`` (identity and 1 for other formats, whose world nerfstudio's transform starts
    from)."""
    applied, scale = np.eye(4), 1.0
    path = os.path.join(capture, "transforms.json")
    if not os.path.isfile(path):
        return applied, scale
    meta = _read_json(path, "a transforms.json")
    if not isinstance(meta, dict):
        raise ValueError(f"{path}: not a transforms.json (a JSON object)")
    if "applied_transform" in meta:
        applied[:3, :4] = _matrix(meta["applied_transform"], path, "applied_transform", ((3, 4), (4, 4)))[:3, :4]
    elif os.path.isdir(os.path.join(capture, "colmap", "sparse", "0")):
        applied[:3, :4] = COLMAP_APPLIED
    if "applied_scale" in meta:
        scale = _positive(meta, path, "applied_scale")
    return applied, scale


def _matrix(value, path, key, shapes):
    """``value`` as a float64 array of one of ``shapes`` with finite entries, else one line naming the
    file and key."""
    try:
        m = np.asarray(value, np.float64)
    except (TypeError, ValueError):
        m = None
    if m is None or m.shape not in shapes or not np.all(np.isfinite(m)):
        want = " or ".join("x".join(map(str, s)) if len(s) > 1 else f"{s[0]} numbers" for s in shapes)
        got = "non-numbers" if m is None else "non-finite numbers" if m.shape in shapes else f"shape {m.shape}"
        raise ValueError(f"{path}: '{key}' must be {want}, all finite; got {got}")
    return m


def _positive(data, path, key, whole=False):
    """``data[key]`` as a positive (whole) number, else one line naming the file and key."""
    value = data.get(key)
    ok = not isinstance(value, bool) and isinstance(value, (int, float)) and np.isfinite(value) and value > 0
    if not ok or (whole and value != int(value)):
        raise ValueError(f"{path}: '{key}' must be a positive {'whole ' if whole else ''}number, got "
                         f"{json.dumps(value)}")
    return int(value) if whole else float(value)


def read_nerfstudio_path(path, dataparser=None, capture=None):
    """Cameras of a nerfstudio ``camera_path.json`` in the world of the capture folder ``capture``
    (its ``applied_transform``, ``applied_scale``), through ``dataparser`` (its
    ``dataparser_transforms.json``) when given (see the module docstring). Every field is checked,
    the message naming the file and the key (a NaN pose is refused, not rendered black)."""
    data = _read_json(path, "a nerfstudio camera path")
    if not isinstance(data, dict) or "camera_path" not in data:
        raise ValueError(f"{path}: not a nerfstudio camera path (a JSON object with 'camera_path', 'render_width' "
                         "and 'render_height'; it has no 'camera_path')")
    width, height = _positive(data, path, "render_width", True), _positive(data, path, "render_height", True)
    entries = data.get("camera_path")
    if not isinstance(entries, list) or not entries:
        raise ValueError(f"{path}: 'camera_path' must be a non-empty list of cameras, got "
                         f"{json.dumps(entries) if entries is None or not isinstance(entries, list) else '[]'}")
    kind = str(data.get("camera_type", "perspective"))
    if kind.lower() != "perspective":
        raise ValueError(f"{path}: camera_type '{kind}' is not supported (only perspective cameras render)")
    back = np.eye(4)
    if dataparser is not None:
        dp = _read_json(dataparser, "a dataparser_transforms.json")
        if not isinstance(dp, dict) or "transform" not in dp:
            raise ValueError(f"{dataparser}: not a dataparser_transforms.json (an object with 'transform' and 'scale')")
        t = np.eye(4)
        t[:3, :4] = _matrix(dp["transform"], dataparser, "transform", ((3, 4), (4, 4)))[:3, :4]
        if abs(np.linalg.det(t[:3, :3])) < 1e-12:
            raise ValueError(f"{dataparser}: 'transform' is singular (it maps the capture onto a plane or less)")
        scale = _positive(dp, dataparser, "scale")
        applied, applied_scale = capture_applied(capture) if capture else (np.eye(4), 1.0)
        back = applied @ np.linalg.inv(t) @ np.diag([applied_scale / scale] * 3 + [1.0])
    out = []
    for k, entry in enumerate(entries):
        if not isinstance(entry, dict):
            raise ValueError(f"{path}: camera_path[{k}] must be an object with 'camera_to_world' and 'fov'")
        c2w = _matrix(entry.get("camera_to_world"), path, f"camera_path[{k}].camera_to_world", ((16,), (4, 4)))
        fov_y = entry.get("fov")
        if isinstance(fov_y, bool) or not isinstance(fov_y, (int, float)) or not 0 < fov_y < 180:
            raise ValueError(f"{path}: camera_path[{k}].fov must be a vertical field of view in (0, 180) degrees, "
                             f"got {json.dumps(entry.get('fov'))}")
        c2w = back @ c2w.reshape(4, 4)
        norms = np.linalg.norm(c2w[:3, :3], axis=0)
        if not np.all(norms > 1e-12):
            raise ValueError(f"{path}: camera_path[{k}].camera_to_world has no rotation (a zero column)")
        c2w[:3, :3] /= norms  # the viewer's scale is not the camera's
        fov_x = np.degrees(2 * np.arctan(np.tan(np.radians(float(fov_y)) / 2) * width / height))
        out.append(Camera(opengl_to_mitsuba(c2w), float(fov_x), width, height))
    return out


def nerfstudio_fps(path):
    """The frame rate nerfstudio renders a ``camera_path.json`` at: its frames over its ``seconds``;
    None without ``seconds``."""
    data = _read_json(path, "a nerfstudio camera path")
    if "seconds" not in data:
        return None
    try:
        seconds = float(data["seconds"])
    except (TypeError, ValueError):
        seconds = float("nan")
    if not seconds > 0:
        raise ValueError(f"{path}: 'seconds' must be a positive number, got {data['seconds']!r}")
    return len(data["camera_path"]) / seconds
