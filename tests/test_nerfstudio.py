"""nerfstudio's transforms.json conventions, read as its dataparser reads them: fl_y without distortion,
the perspective model's k4 (its ``radial_and_tangential_undistort``), the split lists and the
pixels-to-ignore ``mask_path``; each checked on what the loaded views and the training batches show."""
import json
import os

import imageio.v3 as iio
import numpy as np
import pytest

from mi_voldis.cameras import pixel_rays
from mi_voldis.data import DatasetError, load_dataset
from mi_voldis.data.lens import Lens, lens_from_opencv_keys
from mi_voldis.fit.background import background_ray_pool
from mi_voldis.raybank import RayBank

W, H = 48, 36


def pattern(x, y):
    """A smooth RGB function of normalised OpenCV image coordinates (x right, y down at unit depth)."""
    return np.stack([0.5 + 0.4 * np.sin(7 * x), 0.5 + 0.4 * np.cos(6 * y), 0.5 + 0.3 * np.sin(5 * x + 4 * y)], -1)


def nerfstudio_distort(x, y, k1=0.0, k2=0.0, k3=0.0, k4=0.0, p1=0.0, p2=0.0):
    """nerfstudio's perspective lens (cameras/camera_utils.py): r = x^2 + y^2,
    d = 1 + k1 r + k2 r^2 + k3 r^3 + k4 r^4, xd = x d + 2 p1 x y + p2 (r + 2 x^2),
    yd = y d + 2 p2 x y + p1 (r + 2 y^2)."""
    r = x * x + y * y
    d = 1 + k1 * r + k2 * r ** 2 + k3 * r ** 3 + k4 * r ** 4
    return x * d + 2 * p1 * x * y + p2 * (r + 2 * x * x), y * d + 2 * p2 * x * y + p1 * (r + 2 * y * y)


def nerfstudio_photo(fx, fy, cx, cy, **k):
    """What nerfstudio's camera photographs of :func:`pattern`: each pixel centre's undistorted ray by
    Newton's method on :func:`nerfstudio_distort` (as its radial_and_tangential_undistort)."""
    u, v = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    xd, yd = (u - cx) / fx, (v - cy) / fy
    x, y, eps = xd.copy(), yd.copy(), 1e-6
    for _ in range(30):
        fx0, fy0 = nerfstudio_distort(x, y, **k)
        ax, ay = [(a - b) / eps for a, b in zip(nerfstudio_distort(x + eps, y, **k), (fx0, fy0))]
        bx, by = [(a - b) / eps for a, b in zip(nerfstudio_distort(x, y + eps, **k), (fx0, fy0))]
        rx, ry = fx0 - xd, fy0 - yd
        det = ax * by - bx * ay
        x, y = x - (by * rx - bx * ry) / det, y - (ax * ry - ay * rx) / det
    assert np.abs(np.stack(nerfstudio_distort(x, y, **k)) - np.stack([xd, yd])).max() < 1e-9
    return pattern(x, y).astype(np.float32)


def what_the_camera_sees(cam):
    """:func:`pattern` through the loaded Mitsuba camera's own pixel rays (an OpenGL camera at the
    origin looking down -z: OpenCV's normalised coordinates are (x, -y) / -z of the world ray)."""
    px, py = np.meshgrid(np.arange(cam.width) + 0.5, np.arange(cam.height) + 0.5)
    _, d = pixel_rays(cam, px.ravel(), py.ravel())
    x, y = d[:, 0] / -d[:, 2], -d[:, 1] / -d[:, 2]
    return pattern(x.reshape(cam.height, cam.width), y.reshape(cam.height, cam.width))


def write_capture(root, photos, top, frame_keys=None):
    os.makedirs(os.path.join(root, "images"), exist_ok=True)
    frames = []
    for k, photo in enumerate(photos):
        iio.imwrite(os.path.join(root, "images", f"f{k}.png"), np.round(np.clip(photo, 0, 1) * 255).astype(np.uint8))
        frames.append({"file_path": f"images/f{k}.png", "transform_matrix": np.eye(4).tolist(),
                       **((frame_keys or {}).get(k, {}))})
    with open(os.path.join(root, "transforms.json"), "w") as f:
        json.dump({"w": W, "h": H, "aabb": [[-1, -1, -3], [1, 1, -1]], "forward_facing": False, **top,
                   "frames": frames}, f)


def test_fl_y_is_kept_without_distortion(tmp_path):
    """ns-process-data's PINHOLE camera with fl_x 60, fl_y 66, k = 0: the loaded view, through the loaded
    camera's rays, shows what that camera photographed (the 10% vertical scale included)."""
    intr = {"fl_x": 60.0, "fl_y": 66.0, "cx": 24.0, "cy": 18.0}
    photo = nerfstudio_photo(60.0, 66.0, 24.0, 18.0)
    write_capture(str(tmp_path), [photo], {"camera_model": "PINHOLE", **intr})
    ds = load_dataset(str(tmp_path), holdout=0)
    want = what_the_camera_sees(ds.cameras[0])
    inner = (slice(3, -3), slice(3, -3))
    assert np.abs(ds.images[0] - want)[inner].max() < 0.02
    assert np.abs(photo - want)[inner].max() > 0.05  # reading fx = fy = 60 would be this wrong


def test_k4_is_nerfstudios_r8_term(tmp_path):
    """OPENCV with k1..k4, p1, p2 (what nerfstudio's Metashape import writes): Lens.distort is nerfstudio's
    polynomial, and the loaded view shows the pattern its camera saw; OpenCV's rational k4 would not."""
    k = {"k1": -0.15, "k2": 0.05, "k3": 0.02, "k4": 1.0, "p1": 0.002, "p2": -0.003}
    intr = {"fl_x": 40.0, "fl_y": 41.0, "cx": 24.5, "cy": 17.5}
    lens = lens_from_opencv_keys("OPENCV", {**intr, **k}, nerfstudio=True)
    x, y = np.meshgrid(np.linspace(-0.7, 0.7, 9), np.linspace(-0.5, 0.5, 7))
    np.testing.assert_allclose(np.stack(lens.distort(x, y)), np.stack(nerfstudio_distort(x, y, **k)), atol=1e-12)
    photo = nerfstudio_photo(40.0, 41.0, 24.5, 17.5, **k)
    write_capture(str(tmp_path), [photo], {"camera_model": "OPENCV", **intr, **k})
    ds = load_dataset(str(tmp_path), holdout=0)
    want = what_the_camera_sees(ds.cameras[0])
    inner = (slice(4, -4), slice(4, -4))
    assert np.abs(ds.images[0] - want)[inner].max() < 0.03
    rational = Lens("OPENCV", 40.0, 41.0, 24.5, 17.5, (k["k1"], k["k2"], k["p1"], k["p2"], k["k3"], k["k4"]))
    assert np.abs(rational.undistorter(W, H)[1](photo) - want)[inner].max() > 0.1


def test_split_lists_give_the_split(tmp_path):
    """train_filenames / test_filenames (paths as nerfstudio writes them, normalised as it resolves
    them): listed frames get their split, a frame in neither list is left out; a name no frame has is
    one line naming the key."""
    root = str(tmp_path)
    photos = [np.full((H, W, 3), 0.2 * k, np.float32) for k in range(4)]
    top = {"fl_x": 40.0, "train_filenames": ["images/f0.png", "./images/f2.png"], "test_filenames": ["images/f3.png"]}
    write_capture(root, photos, top)
    ds = load_dataset(root)
    assert ds.names == ["f0.png", "f2.png", "f3.png"] and list(ds.split) == ["train", "train", "test"]
    assert any("left out" in n for n in ds.meta["notes"])
    write_capture(root, photos, {"fl_x": 40.0, "test_filenames": ["images/f1.png"]})
    assert list(load_dataset(root).split) == ["train", "test", "train", "train"]
    write_capture(root, photos, {"fl_x": 40.0, "test_filenames": ["images/f9.png"]})
    with pytest.raises(DatasetError, match=r"transforms.json: 'test_filenames' lists 'images/f9.png', which no frame"):
        load_dataset(root)


def test_mask_path_pixels_are_left_out_of_training(tmp_path):
    """nerfstudio's mask_path (black = ignore): read into Dataset.ignore, and neither the training
    batches nor the background's ray pool draw those pixels (red in the photos, so a batch would show
    them)."""
    root = str(tmp_path)
    photos = []
    for k in range(3):
        p = np.full((H, W, 3), 0.5, np.float32)
        p[:, :10] = (1.0, 0.0, 0.0)
        photos.append(p)
    os.makedirs(tmp_path / "ignore")
    keep = np.full((H, W), 255, np.uint8)
    keep[:, :10] = 0
    iio.imwrite(tmp_path / "ignore" / "m.png", keep)
    os.makedirs(tmp_path / "masks")
    for k in range(3):
        m = np.zeros((H, W), np.uint8)
        m[10:20, 20:30] = 255
        iio.imwrite(tmp_path / "masks" / f"f{k}.png", m)
    write_capture(root, photos, {"fl_x": 40.0}, {k: {"mask_path": "ignore/m.png"} for k in (0, 2)})
    ds = load_dataset(root, holdout=0)
    assert ds.ignore[0, :, :10].all() and not ds.ignore[0, :, 10:].any() and not ds.ignore[1].any()
    bank = RayBank(ds, ds.train)
    _, _, color, _, view = bank.batch(np.random.default_rng(0), 4000)
    color, view = np.array(color).reshape(3, -1).T, np.array(view)
    red = (color[:, 0] > 0.9) & (color[:, 1] < 0.1)
    assert red.any() and set(view[red]) == {1}  # only the frame without a mask_path shows its red band
    pool = background_ray_pool(ds, bank, 1.0)
    px = pool % W
    assert len(pool) and not ((pool // (H * W) != 1) & (px < 10)).any()
    assert ((pool // (H * W) == 1) & (px < 10)).any()
