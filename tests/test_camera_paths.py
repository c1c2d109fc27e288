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


def rigid(angle_deg, axis, t):
    """4x4 rotation about ``axis`` (Rodrigues) then translation ``t``."""
    a, k = np.radians(angle_deg), np.asarray(axis, np.float64) / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    m = np.eye(4)
    m[:3, :3] = np.eye(3) + np.sin(a) * kx + (1 - np.cos(a)) * kx @ kx
    m[:3, 3] = t
    return m


def test_nerfstudio_path_lands_where_nerfstudio_puts_the_capture(tmp_path):
    """A capture whose applied_transform A is not the identity and whose applied_scale a is 0.5. By
    nerfstudio_dataparser.py: its poses are oriented and centred (O), then scaled by s (auto scale);
    dataparser_transforms.json holds transform = O @ [A; 0 0 0 1] and scale = s * a. A camera path
    of the dataset's own poses as nerfstudio holds them, read with both files, gives the dataset's
    cameras back."""
    cams = orbit(3, TARGET, 2.0, (10, 40), 50.0, 40, 30)
    applied = rigid(90, [1, 0, 0], [0.0, 0.0, 0.0]) @ rigid(35, [0.2, 1, 0.1], [1.5, -2.0, 0.7])
    applied_scale = 0.5
    orient = rigid(-20, [0.3, 0.1, 1], [-0.4, 0.9, 2.0])
    s = 0.37
    capture = tmp_path / "capture"
    capture.mkdir()
    (capture / "transforms.json").write_text(json.dumps({"applied_transform": applied[:3].tolist(),
                                                         "applied_scale": applied_scale, "frames": []}))
    entries = []
    for c in cams:
        pose = orient @ mitsuba_to_opengl(c.to_world)  # auto_orient_and_center_poses, then the scale
        pose[:3, 3] *= s
        fov_y = np.degrees(2 * np.arctan(np.tan(np.radians(c.fov_x) / 2) * c.height / c.width))
        entries.append({"camera_to_world": pose.ravel().tolist(), "fov": fov_y})
    path = tmp_path / "camera_path.json"
    path.write_text(json.dumps({"render_width": 40, "render_height": 30, "camera_path": entries, "seconds": 1.5}))
    dp = tmp_path / "dataparser_transforms.json"
    dp.write_text(json.dumps({"transform": (orient @ applied)[:3].tolist(), "scale": s * applied_scale}))
    back = camera_paths.read_nerfstudio_path(str(path), str(dp), str(capture))
    for a, b in zip(back, cams):
        np.testing.assert_allclose(a.to_world, b.to_world, atol=1e-9)
    ignored = camera_paths.read_nerfstudio_path(str(path), str(dp))  # without the capture's A and a
    assert np.linalg.norm(ignored[0].to_world[:3, 3] - cams[0].to_world[:3, 3]) > 1.0
    assert camera_paths.nerfstudio_fps(str(path)) == pytest.approx(2.0)  # nerfstudio: len(cameras) / seconds


@pytest.mark.parametrize("kind", ["equirectangular", "fisheye", "omnidirectional"])
def test_nerfstudio_path_refuses_other_camera_types(tmp_path, kind):
    path = tmp_path / "camera_path.json"
    path.write_text(json.dumps({"render_width": 40, "render_height": 20, "camera_type": kind, "camera_path": [
        {"camera_to_world": np.eye(4).ravel().tolist(), "fov": 50}]}))
    with pytest.raises(ValueError, match=f"camera_path.json: camera_type '{kind}' is not supported"):
        camera_paths.read_nerfstudio_path(str(path))


def test_render_nerfstudio_path_at_its_frame_rate(tiny_run, tmp_path):
    """2 frames over 1 s: the video runs at 2 frames per second, as nerfstudio renders it."""
    import imageio.v3 as iio
    from test_bad_inputs import _boundary, script

    from mi_voldis.data import load_dataset
    with open(os.path.join(tiny_run, "config.json")) as f:
        cams = load_dataset(json.load(f)["dataset"]["path"]).cameras[:2]
    path = tmp_path / "camera_path.json"
    path.write_text(json.dumps({"render_width": 16, "render_height": 12, "seconds": 1.0, "camera_path": [
        {"camera_to_world": mitsuba_to_opengl(c.to_world).ravel().tolist(), "fov": 40.0} for c in cams]}))
    out = tmp_path / "ns"
    assert _boundary.run(script("render").main, [os.path.join(tiny_run, "scene.xml"), "--out", str(out),
                                                 "--path", str(path), "--spp", "1"]) == 0
    video = next(out.glob("composite.*"))
    meta = iio.immeta(video)
    fps = meta["fps"] if video.suffix == ".mp4" else 1000.0 / meta["duration"]  # GIF: ms per frame
    assert fps == pytest.approx(2.0)


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
