"""Camera paths: the orbit's geometry, interpolation through the views, nerfstudio's camera_path.json
read back through a dataparser transform, and render.py --path writing frames and a video."""
import json
import os

import numpy as np
import pytest

from mi_voldis import camera_paths
from mi_voldis.cameras import Camera
from mi_voldis.data.conventions import mitsuba_to_opengl
from mi_voldis.synth.rigs import look_at, orbit
from mi_voldis.transforms import quaternion_to_rotation, rotation_to_quaternion

TARGET = np.array([0.3, -0.2, 0.1])


def test_orbit_circles_the_target_looking_at_it():
    cams = orbit(12, TARGET, 2.5, (20, 40), 45.0, 32, 24)
    path = camera_paths.make_path("orbit", cams, 16)
    pos = np.array([c.to_world[:3, 3] for c in path])
    dist = np.linalg.norm(pos - TARGET, axis=1)
    assert np.ptp(dist) < 1e-9 and 1.5 < dist[0] < 2.6
    for c, p in zip(path, pos):
        forward = c.to_world[:3, 2]
        np.testing.assert_allclose(forward, (TARGET - p) / np.linalg.norm(TARGET - p), atol=1e-6)
    steps = np.linalg.norm(np.diff(pos, axis=0), axis=1)
    assert np.ptp(steps) < 1e-9  # even steps


def test_interpolation_passes_through_the_views():
    cams = orbit(4, TARGET, 2.0, (10, 50), 45.0, 32, 24)
    path = camera_paths.make_path("interpolate", cams, 7)  # frames 0, 2, 4, 6 are the views
    for k, c in enumerate(cams):
        np.testing.assert_allclose(path[2 * k].to_world, c.to_world, atol=1e-9)
    mid = path[1].to_world
    np.testing.assert_allclose(mid[:3, 3], 0.5 * (cams[0].to_world[:3, 3] + cams[1].to_world[:3, 3]), atol=1e-9)
    np.testing.assert_allclose(mid[:3, :3].T @ mid[:3, :3], np.eye(3), atol=1e-9)  # a rotation
    q = rotation_to_quaternion(cams[2].to_world[:3, :3])
    np.testing.assert_allclose(quaternion_to_rotation(q), cams[2].to_world[:3, :3], atol=1e-12)


def test_spiral_stays_near_the_forward_rig():
    cams = [Camera(look_at([0.1 * (k % 3), 0.1 * (k // 3), 0], [0.1 * (k % 3), 0.1 * (k // 3), 5]), 50.0, 32, 24)
            for k in range(9)]
    path = camera_paths.make_path("spiral", cams, 20, near_far=np.array([[2.0, 8.0]]))
    pos = np.array([c.to_world[:3, 3] for c in path])
    assert np.all(np.abs(pos - pos.mean(axis=0)) < 0.5) and np.ptp(pos[:, 0]) > 0.1
    assert all(c.to_world[2, 2] > 0.9 for c in path)  # still looking down +z


def test_nerfstudio_camera_path_through_a_dataparser_transform(tmp_path):
    cams = orbit(3, TARGET, 2.0, (10, 40), 50.0, 40, 30)
    angle = np.radians(30)
    t = np.eye(4)
    t[:3, :3] = [[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]]
    t[:3, 3] = [0.5, -1.0, 0.2]
    scale = 0.4
    entries = []
    for c in cams:
        c2w = mitsuba_to_opengl(c.to_world)
        viewer = np.diag([scale, scale, scale, 1.0]) @ t @ c2w  # positions and rotations in the viewer's frame
        fov_y = np.degrees(2 * np.arctan(np.tan(np.radians(c.fov_x) / 2) * c.height / c.width))
        entries.append({"camera_to_world": viewer.ravel().tolist(), "fov": fov_y, "aspect": 40 / 30})
    path = tmp_path / "camera_path.json"
    path.write_text(json.dumps({"render_width": 40, "render_height": 30, "camera_path": entries}))
    dp = tmp_path / "dataparser_transforms.json"
    dp.write_text(json.dumps({"transform": t[:3].tolist(), "scale": scale}))
    back = camera_paths.read_nerfstudio_path(str(path), str(dp))
    for a, b in zip(back, cams):
        np.testing.assert_allclose(a.to_world, b.to_world, atol=1e-9)
        assert a.fov_x == pytest.approx(b.fov_x) and (a.width, a.height) == (40, 30)
    path.write_text("{}")
    with pytest.raises(ValueError, match="not a nerfstudio camera path"):
        camera_paths.read_nerfstudio_path(str(path))


def test_render_path_writes_frames_and_a_video(tiny_run, tmp_path, capsys):
    from test_bad_inputs import _boundary, script
    out = str(tmp_path / "orbit")
    scene = os.path.join(tiny_run, "scene.xml")
    assert _boundary.run(script("render").main, [scene, "--out", out, "--path", "orbit", "--frames", "3",
                                                 "--layer", "fg"]) == 0
    files = sorted(os.listdir(out))
    assert [f for f in files if f.startswith("frame")] == ["frame_0000.exr", "frame_0001.exr", "frame_0002.exr"]
    assert any(f.startswith("fg.") and f.endswith((".mp4", ".gif")) for f in files)
    assert _boundary.run(script("render").main, [scene, "--out", out, "--path", "zigzag"]) == 1
    assert "--path must be orbit, spiral, interpolate or a camera_path.json" in capsys.readouterr().err
