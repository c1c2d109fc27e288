"""Captures as users bring them: lens distortion, COLMAP models, nerfstudio's transforms.json keys,
EXR and alpha-channel masks, linear images, partial masks, downscaled folders, the SPIn-NeRF layout
and the dataset record a run keeps."""
import json
import os
import struct

import cv2
import imageio.v3 as iio
import numpy as np
import pytest

from mi_voldis.cameras import Camera, pixel_rays
from mi_voldis.data import DatasetError, load_dataset
from mi_voldis.data.conventions import mitsuba_to_opengl
from mi_voldis.data.lens import COLMAP_IDS, Lens
from mi_voldis.data.llff import write_llff
from mi_voldis.io.exr import write_exr
from mi_voldis.io.images import linear_to_srgb
from mi_voldis.synth.rigs import look_at
from mi_voldis.transforms import rotation_to_quaternion

W, H = 48, 36


def pattern(x, y):
    """A smooth RGB function of normalised image coordinates (x right, y down at unit depth)."""
    return np.stack([0.5 + 0.4 * np.sin(7 * x), 0.5 + 0.4 * np.cos(6 * y), 0.5 + 0.3 * np.sin(5 * x + 4 * y)], -1)


def distorted_photo(lens, w=W, h=H):
    """What a camera with ``lens`` photographs of :func:`pattern`: each pixel's normalised ray from
    OpenCV's inverse of the lens model."""
    u, v = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    pts = np.stack([u, v], -1).reshape(-1, 1, 2).astype(np.float64)
    k = np.array([[lens.fx, 0, lens.cx], [0, lens.fy, lens.cy], [0, 0, 1]])
    if lens.fisheye:
        n = cv2.fisheye.undistortPoints(pts, k, np.asarray(lens.coeffs[:4], np.float64))
    else:
        n = cv2.undistortPoints(pts, k, np.asarray(lens.coeffs, np.float64),
                                criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-10))
    n = n.reshape(h, w, 2)
    return pattern(n[..., 0], n[..., 1]).astype(np.float32)


def normalised_of(cam, opencv_c2w=None):
    """Normalised OpenCV coordinates of every pixel ray of a Mitsuba camera whose OpenCV
    camera-to-world is ``opencv_c2w`` (identity: the camera at the origin)."""
    px, py = np.meshgrid(np.arange(cam.width) + 0.5, np.arange(cam.height) + 0.5)
    _, d = pixel_rays(cam, px.ravel(), py.ravel())
    m = np.eye(4) if opencv_c2w is None else opencv_c2w
    local = d @ m[:3, :3]
    return (local[:, 0] / local[:, 2]).reshape(cam.height, cam.width), (local[:, 1] / local[:, 2]).reshape(
        cam.height, cam.width)


@pytest.mark.parametrize("lens", [
    Lens("OPENCV", 40.0, 40.0, 24.5, 17.0, (-0.25, 0.06, 0.004, -0.003)),
    Lens("FULL_OPENCV", 40.0, 41.0, 23.0, 18.5, (-0.1, 0.02, 0.0, 0.002, 0.001, 0.05, 0.0, 0.01)),
    Lens("OPENCV_FISHEYE", 30.0, 30.0, 24.0, 18.0, (0.08, -0.02, 0.01, -0.002)),
])
def test_undistortion_gives_the_pinhole_photo(lens):
    """Undistorting a distorted photo of an analytic pattern gives the pinhole camera's photo of it:
    pixel (u, v) of K' shows pattern((u - cx) / f, (v - cy) / f)."""
    (f, cx, cy), resample = lens.undistorter(W, H)
    out = resample(distorted_photo(lens))
    u, v = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    want = pattern((u - cx) / f, (v - cy) / f)
    inner = (slice(4, -4), slice(4, -4))  # the border repeats pixels the lens did not see
    assert np.abs(out[inner] - want[inner]).max() < 0.02
    assert np.abs(distorted_photo(lens)[inner] - want[inner]).max() > 0.05  # the lens mattered


def write_json(root, meta):
    with open(os.path.join(root, "transforms.json"), "w") as f:
        json.dump(meta, f)


def test_nerfstudio_opencv_capture_is_undistorted(tmp_path):
    """transforms.json with camera_model OPENCV: the loaded view, through the loaded camera's own pixel
    rays, shows the pattern the lens saw (per-frame intrinsics on the second frame)."""
    lenses = [Lens("OPENCV", 40.0, 40.0, 24.0, 18.0, (-0.2, 0.05, 0.003, -0.002)),
              Lens("OPENCV", 44.0, 44.0, 23.5, 18.5, (0.1, -0.02, 0.0, 0.0))]
    os.makedirs(tmp_path / "images")
    frames = []
    for k, lens in enumerate(lenses):
        iio.imwrite(tmp_path / "images" / f"f{k}.png", np.round(distorted_photo(lens) * 255).astype(np.uint8))
        frames.append({"file_path": f"images/f{k}.png", "transform_matrix": np.eye(4).tolist()})
    keys = lambda lens: {"fl_x": lens.fx, "fl_y": lens.fy, "cx": lens.cx, "cy": lens.cy,  # noqa: E731
                         "k1": lens.coeffs[0], "k2": lens.coeffs[1], "p1": lens.coeffs[2], "p2": lens.coeffs[3]}
    frames[1].update(keys(lenses[1]))
    write_json(tmp_path, {"camera_model": "OPENCV", "w": W, "h": H, **keys(lenses[0]), "frames": frames,
                          "aabb": [[-1, -1, -3], [1, 1, -1]], "forward_facing": False})
    ds = load_dataset(str(tmp_path), holdout=0)
    assert any("undistorted" in n for n in ds.meta["notes"])
    for k in range(2):
        # OpenGL camera at the origin: OpenCV axes are (x, -y, -z) of the world
        x, y = normalised_of(ds.cameras[k], np.diag([1.0, -1.0, -1.0, 1.0]))
        err = np.abs(ds.images[k] - pattern(x, y))[4:-4, 4:-4]
        assert err.max() < 0.03, (k, err.max())
    assert ds.cameras[1].focal == pytest.approx(44.0) and ds.cameras[0].focal == pytest.approx(40.0)


# ------------------------------------------------------------------------------------- COLMAP
def ring(n=4):
    return [Camera(look_at([3 * np.sin(k), 0.4, 3 * np.cos(k)], [0, 0, 0]), 50.0, W, H) for k in range(n)]


def colmap_pose(cam):
    """(qvec, tvec) of a Mitsuba camera: world-to-camera in OpenCV axes."""
    c2w = np.asarray(cam.to_world) @ np.diag([-1.0, -1.0, 1.0, 1.0])
    w2c = np.linalg.inv(c2w)
    return rotation_to_quaternion(w2c[:3, :3]), w2c[:3, 3]


def write_colmap(root, cams, names, model="PINHOLE", params=None, binary=True, points=None):
    d = os.path.join(root, "sparse", "0")
    os.makedirs(d, exist_ok=True)
    f = cams[0].focal
    params = params or ([f, f, W / 2, H / 2] if model == "PINHOLE" else [f, W / 2, H / 2, 0.0])
    points = np.zeros((0, 3)) if points is None else points
    poses = [colmap_pose(c) for c in cams]
    if binary:
        with open(os.path.join(d, "cameras.bin"), "wb") as fh:
            fh.write(struct.pack("<QiiQQ", 1, 1, COLMAP_IDS[model], W, H) + struct.pack(f"<{len(params)}d", *params))
        with open(os.path.join(d, "images.bin"), "wb") as fh:
            fh.write(struct.pack("<Q", len(cams)))
            for k, ((q, t), name) in enumerate(zip(poses, names)):
                fh.write(struct.pack("<idddddddi", k + 1, *q, *t, 1) + name.encode() + b"\0")
                fh.write(struct.pack("<Q", 1) + struct.pack("<ddq", 1.0, 2.0, -1))
        with open(os.path.join(d, "points3D.bin"), "wb") as fh:
            fh.write(struct.pack("<Q", len(points)))
            for k, p in enumerate(points):
                fh.write(struct.pack("<qdddBBBd", k, *p, 1, 2, 3, 0.5) + struct.pack("<Qii", 1, 1, 0))
    else:
        with open(os.path.join(d, "cameras.txt"), "w") as fh:
            fh.write("# CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n")
            fh.write(f"1 {model} {W} {H} {' '.join(repr(float(p)) for p in params)}\n")
        with open(os.path.join(d, "images.txt"), "w") as fh:
            fh.write("# IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n")
            for k, ((q, t), name) in enumerate(zip(poses, names)):
                fh.write(f"{k + 1} {' '.join(repr(float(v)) for v in (*q, *t))} 1 {name}\n\n")  # empty 2D points
        with open(os.path.join(d, "points3D.txt"), "w") as fh:
            for k, p in enumerate(points):
                fh.write(f"{k} {p[0]} {p[1]} {p[2]} 1 2 3 0.5 1 0\n")


@pytest.mark.parametrize("binary", [True, False])
def test_colmap_model_gives_the_cameras(tmp_path, binary):
    cams = ring()
    os.makedirs(tmp_path / "images")
    names = []
    for k in range(len(cams)):
        names.append(f"v{k}.png")
        iio.imwrite(tmp_path / "images" / names[-1], np.full((H, W, 3), 40 * k, np.uint8))
    rng = np.random.default_rng(0)
    points = rng.uniform(-0.5, 0.5, (50, 3))
    write_colmap(str(tmp_path), cams, names, binary=binary, points=points)
    ds = load_dataset(str(tmp_path), holdout=0)
    assert ds.meta["format"] == "colmap" and ds.names == names and ds.box.kind == "world"
    np.testing.assert_allclose(ds.points, points, atol=1e-12)
    for a, b in zip(ds.cameras, cams):
        np.testing.assert_allclose(a.to_world, b.to_world, atol=1e-9)
        assert a.fov_x == pytest.approx(b.fov_x) and a.principal == pytest.approx(b.principal)
    assert np.all(ds.box.lo <= points.min(axis=0) + 0.1) and np.all(ds.box.hi >= points.max(axis=0) - 0.1)


def test_colmap_refuses_a_model_it_cannot_undistort(tmp_path):
    cams = ring(2)
    os.makedirs(tmp_path / "images")
    for k in range(2):
        iio.imwrite(tmp_path / "images" / f"v{k}.png", np.zeros((H, W, 3), np.uint8))
    write_colmap(str(tmp_path), cams, ["v0.png", "v1.png"], model="FOV", params=[40.0, 40.0, 24.0, 18.0, 0.5])
    with pytest.raises(DatasetError, match="sparse.0: camera 1: .*FOV cannot be undistorted"):
        load_dataset(str(tmp_path))


# ------------------------------------------------------------------------------------- masks and colour
def small_transforms(root, n=3, **top):
    cams = ring(n)
    os.makedirs(os.path.join(root, "images"), exist_ok=True)
    rng = np.random.default_rng(1)
    names = []
    for k in range(n):
        names.append(f"img_{k}.png")
        iio.imwrite(os.path.join(root, "images", names[-1]), rng.integers(0, 255, (H, W, 3), dtype=np.uint8))
    meta = {"fl_x": cams[0].focal, "w": W, "h": H, "aabb": [[-1, -1, -1], [1, 1, 1]],
            "frames": [{"file_path": f"images/{n}", "transform_matrix": mitsuba_to_opengl(c.to_world).tolist()}
                       for c, n in zip(cams, names)], **top}
    write_json(root, meta)
    return meta, names


def box_mask(k):
    m = np.zeros((H, W), np.float32)
    m[8:20, 10 + k:26 + k] = 1.0
    return m


def test_exr_masks_alpha_mattes_and_missing_masks(tmp_path):
    """One view's mask as a single-channel EXR, one as an RGBA PNG whose matte is only in alpha, one
    missing: the first two read as stored, the third view trains the full scene only (a note says so)."""
    root = str(tmp_path)
    _, names = small_transforms(root)
    os.makedirs(tmp_path / "masks")
    write_exr(str(tmp_path / "masks" / "img_0.exr"), {"Y": box_mask(0)})
    rgba = np.zeros((H, W, 4), np.uint8)
    rgba[..., 3] = (box_mask(1) * 255).astype(np.uint8)
    iio.imwrite(tmp_path / "masks" / "img_1.png", rgba)
    ds = load_dataset(root, holdout=0)
    np.testing.assert_array_equal(ds.masks[0], box_mask(0) > 0.5)
    np.testing.assert_array_equal(ds.masks[1], box_mask(1) > 0.5)
    assert ds.masks[2].all() and list(ds.masked) == [True, True, False]
    assert list(ds.masked_train) == [0, 1]
    assert any("1 of 3 views have no object mask" in n for n in ds.meta["notes"])


def test_linear_exr_images_are_encoded_for_fitting(tmp_path):
    root = str(tmp_path)
    meta, names = small_transforms(root, 2)
    rng = np.random.default_rng(2)
    linear = rng.uniform(0, 1.3, (2, H, W, 3)).astype(np.float32)  # HDR values above 1 are clipped
    for k in range(2):
        write_exr(str(tmp_path / "images" / f"lin_{k}.exr"), {c: linear[k, ..., i] for i, c in enumerate("RGB")})
        meta["frames"][k]["file_path"] = f"images/lin_{k}.exr"
    write_json(root, meta)
    ds = load_dataset(root, holdout=0)
    np.testing.assert_allclose(ds.images, linear_to_srgb(linear), atol=1e-6)
    assert ds.meta["color_space"].startswith("linear")


def test_forward_facing_without_bounds_uses_the_points(tmp_path):
    """No near/far: the bounds come from the ply points (depths 2..6 in front of every camera), or
    NeRF's default near plane when there are none; never a refusal."""
    root = str(tmp_path)
    cams = [Camera(look_at([0.1 * k, 0, 0], [0.1 * k, 0, 5]), 50.0, W, H) for k in range(3)]
    os.makedirs(tmp_path / "images")
    for k in range(3):
        iio.imwrite(tmp_path / "images" / f"f{k}.png", np.zeros((H, W, 3), np.uint8))
    rng = np.random.default_rng(3)
    pts = np.column_stack([rng.uniform(-0.2, 0.2, 400), rng.uniform(-0.2, 0.2, 400), rng.uniform(2, 6, 400)])
    with open(tmp_path / "pc.ply", "w") as f:
        f.write(f"ply\nformat ascii 1.0\nelement vertex {len(pts)}\nproperty float x\nproperty float y\n"
                "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n")
        f.writelines(f"{p[0]} {p[1]} {p[2]} 1 2 3\n" for p in pts)
    meta = {"fl_x": cams[0].focal, "w": W, "h": H, "ply_file_path": "pc.ply",
            "applied_transform": [[0, 1, 0, 0], [1, 0, 0, 0], [0, 0, -1, 0]],
            "frames": [{"file_path": f"images/f{k}.png", "transform_matrix": mitsuba_to_opengl(c.to_world).tolist()}
                       for k, c in enumerate(cams)]}
    write_json(root, meta)
    ds = load_dataset(root, holdout=0)
    near, far = ds.near_far[0]
    assert 2.0 <= near < 2.1 and 5.9 < far <= 6.0 and ds.box.kind == "ndc"
    assert ds.meta["applied_transform"][2][2] == -1
    del meta["ply_file_path"]
    write_json(root, meta)
    ds = load_dataset(root, holdout=0)
    assert ds.near_far[0, 0] == 1.0 and any("NeRF's default" in n for n in ds.meta["notes"])


def test_downscale_reads_images_k_with_scaled_intrinsics(tmp_path):
    root = str(tmp_path)
    meta, names = small_transforms(root, 2)
    meta.update({"fl_x": 2 * meta["fl_x"], "w": 2 * W, "h": 2 * H})  # intrinsics of the full-size photos
    write_json(root, meta)
    os.rename(tmp_path / "images", tmp_path / "images_2")
    with pytest.raises(DatasetError, match="image 'images/img_0.png' not found"):
        load_dataset(root)
    os.makedirs(tmp_path / "masks")
    for k, n in enumerate(names):  # full-resolution masks are reduced to the images
        iio.imwrite(tmp_path / "masks" / n, np.kron(box_mask(k), np.ones((2, 2))).astype(np.uint8) * 255)
    ds = load_dataset(root, factor=2, holdout=0)
    assert ds.size == (H, W) and ds.cameras[0].focal == pytest.approx(meta["fl_x"] / 2)
    np.testing.assert_array_equal(ds.masks[1], box_mask(1) > 0.5)
    assert ds.meta["factor"] == 2


# ------------------------------------------------------------------------------------- SPIn-NeRF
def test_spinnerf_layout(tmp_path):
    """images_4/label/ for the training views, images_4/test_label/ for the object-free test views."""
    root = str(tmp_path)
    cams = [Camera(look_at([0.1 * k, 0, 0], [0.1 * k, 0, 5]), 50.0, W, H) for k in range(5)]
    folder = tmp_path / "images_4"
    os.makedirs(folder / "label")
    os.makedirs(folder / "test_label")
    for k in range(5):
        iio.imwrite(folder / f"{k:03d}.png", np.full((H, W, 3), 10 * k, np.uint8))
        sub = "test_label" if k < 2 else "label"
        iio.imwrite(folder / sub / f"{k:03d}.png", box_mask(k).astype(np.uint8))  # value 1 = object
    write_llff(root, cams, [(1.0, 8.0)] * 5, "images_4")
    ds = load_dataset(root)
    assert list(ds.test) == [0, 1] and list(ds.train) == [2, 3, 4]
    np.testing.assert_array_equal(ds.backgrounds[:2], ds.images[:2])
    assert np.isnan(ds.backgrounds[2:]).all()
    assert all((ds.masks[k] == (box_mask(k) > 0)).all() for k in range(5))


def test_recorded_dataset_loads_as_fitted(tmp_path):
    """A run's record (format, holdout, factor) reloads the views the fit used, so tasks do not
    evaluate on training views after --holdout 4."""
    from mi_voldis.fit.run import dataset_record
    from mi_voldis.tasks.base import load_recorded
    root = str(tmp_path)
    small_transforms(root, 9)
    ds = load_dataset(root, holdout=4)
    record = json.loads(json.dumps(dataset_record(root, ds, 4, None)))
    again = load_recorded(record)
    assert list(again.test) == [0, 4, 8] == list(ds.test) and record["format"] == "transforms"


def test_make_dataset_writes_the_spinnerf_layout(tmp_path):
    """A bundled scene rendered in SPIn-NeRF's layout reads back with the object-free views as test
    views whose photos are the ground truth, spread over the rig."""
    from mi_voldis.synth.make import make_dataset, spinnerf_tests
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = str(tmp_path / "spin")
    make_dataset(os.path.join(root, "scenes", "tabletop.xml"), out, views=10, resolution=(32, 24), spp=2,
                 progress=False, layout="spinnerf")
    assert sorted(os.listdir(out)) == [".mi-voldis", "images_4", "poses_bounds.npy"]  # the marker: make_dataset's
    ds = load_dataset(out)
    assert list(ds.test) == [0, 1, 2, 3] and len(ds.train) == 6
    np.testing.assert_array_equal(ds.backgrounds[ds.test], ds.images[ds.test])
    assert all(ds.masks[v].any() for v in range(10))
    assert spinnerf_tests(10) == [0, 3, 6, 9]  # spread over the rig, not its first four
