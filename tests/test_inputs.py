"""Inputs read as they are: colour modes, alpha, EXR channel names, masks by their value range, degenerate
rigs, contradictory splits and every field of transforms.json, each refused (or noted) in one line that
names the file and the key."""
import json
import os
import re

import imageio.v3 as iio
import numpy as np
import pytest
from PIL import Image

from mi_voldis.cameras import Camera
from mi_voldis.data import DatasetError, check_rig, load_dataset
from mi_voldis.data.conventions import mitsuba_to_opengl
from mi_voldis.data.images import read_image, read_mask
from mi_voldis.data.llff import write_llff
from mi_voldis.io.exr import write_exr
from mi_voldis.synth.rigs import look_at

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
H, W = 18, 24


def transforms(root, n=4, masks=True, **top):
    """A transforms.json dataset of ``n`` random photos around the origin, with box masks; returns
    (meta, image names)."""
    os.makedirs(os.path.join(root, "images"), exist_ok=True)
    rng = np.random.default_rng(1)
    cams = [Camera(look_at([3 * np.sin(k), 0.5, 3 * np.cos(k)], [0, 0, 0]), 45.0, W, H) for k in range(n)]
    names = [f"img_{k:02d}.png" for k in range(n)]
    for name in names:
        iio.imwrite(os.path.join(root, "images", name), rng.integers(0, 255, (H, W, 3), dtype=np.uint8))
    if masks:
        os.makedirs(os.path.join(root, "masks"), exist_ok=True)
        for k, name in enumerate(names):
            m = np.zeros((H, W), np.uint8)
            m[5:10, 6 + k:12 + k] = 255
            iio.imwrite(os.path.join(root, "masks", name), m)
    meta = {"fl_x": cams[0].focal, "w": W, "h": H, "aabb": [[-1, -1, -1], [1, 1, 1]], **top,
            "frames": [{"file_path": f"images/{os.path.splitext(n)[0]}",
                        "transform_matrix": mitsuba_to_opengl(c.to_world).tolist()} for c, n in zip(cams, names)]}
    write_json(root, meta)
    return meta, names


def write_json(root, meta):
    with open(os.path.join(root, "transforms.json"), "w") as f:
        json.dump(meta, f)


# ------------------------------------------------------------------------------------- colour modes
def test_a_cmyk_jpeg_reads_as_its_rgb(tmp_path):
    rgb = np.zeros((H, W, 3), np.uint8)
    rgb[..., 0], rgb[..., 1], rgb[..., 2] = 200, 60, 20
    Image.fromarray(rgb).convert("CMYK").save(tmp_path / "c.jpg", quality=98)
    img = read_image(str(tmp_path / "c.jpg"))
    assert img.shape == (H, W, 3)
    np.testing.assert_allclose(img[H // 2, W // 2], rgb[0, 0] / 255.0, atol=3 / 255)


def test_a_palette_png_reads_as_its_colours(tmp_path):
    rgb = np.zeros((H, W, 3), np.uint8)
    rgb[:, : W // 2] = (255, 0, 0)
    Image.fromarray(rgb).convert("P").save(tmp_path / "p.png")
    img = read_image(str(tmp_path / "p.png"))
    assert np.array_equal(img[0, 0], [1, 0, 0]) and np.array_equal(img[0, -1], [0, 0, 0])


def test_alpha_is_composited_only_where_the_loader_asks(tmp_path):
    """transforms.json: RGBA over background_color (with a note); a capture's photos: RGB as stored,
    alpha left out (with a note); an image transparent everywhere is refused, naming it."""
    rgba = np.zeros((H, W, 4), np.uint8)
    rgba[..., :3] = (10, 100, 200)
    rgba[:, : W // 2, 3] = 255
    path = str(tmp_path / "a.png")
    iio.imwrite(path, rgba)
    over = read_image(path, (0.0, 1.0, 0.0))
    assert np.allclose(over[0, 0], np.array([10, 100, 200]) / 255) and np.array_equal(over[0, -1], [0, 1, 0])
    assert np.allclose(read_image(path, None), np.array([10, 100, 200]) / 255)
    rgba[..., 3] = 0
    iio.imwrite(path, rgba)
    with pytest.raises(DatasetError, match=f"^{path}: every pixel is transparent .alpha 0."):
        read_image(path)

    llff = tmp_path / "llff"
    cams = [Camera(look_at([0.1 * k, 0.0, -3.0], [0.0, 0.0, 0.0]), 50.0, W, H) for k in range(3)]
    os.makedirs(llff / "images")
    write_llff(str(llff), cams, [(1.0, 5.0)] * 3)
    rgba[..., 3] = 0
    rgba[0, 0, 3] = 1  # nearly transparent photos: read as their RGB all the same
    for k in range(3):
        iio.imwrite(llff / "images" / f"{k}.png", rgba)
    ds = load_dataset(str(llff))
    assert np.allclose(ds.images, np.array([10, 100, 200]) / 255, atol=1e-6)
    assert any("3 of 3 photos have an alpha channel" in n and "alpha left out" in n for n in ds.meta["notes"])

    root = str(tmp_path / "tj")
    transforms(root, masks=False, background_color=[0, 0, 0])
    rgba[..., 3] = 255
    rgba[0, 0, 3] = 0
    iio.imwrite(os.path.join(root, "images", "img_01.png"), rgba)
    ds = load_dataset(root)
    assert np.array_equal(ds.images[1, 0, 0], [0, 0, 0]) and ds.meta["background_color"] == [0, 0, 0]
    assert any("RGBA images composited over background_color [0.0, 0.0, 0.0]" in n for n in ds.meta["notes"])


def test_an_exr_of_depth_alone_is_not_a_photo(tmp_path):
    path = str(tmp_path / "z.exr")
    write_exr(path, {"Z": np.ones((H, W))})
    with pytest.raises(DatasetError, match=f"^{path}: the EXR image has no R, G, B or Y channels .it has Z.$"):
        read_image(path)
    assert read_mask(path, "white").all()  # a mask or coverage may be a single channel of any name


# ------------------------------------------------------------------------------------- masks by value range
def test_masks_are_read_by_their_value_range(tmp_path):
    shape = np.zeros((H, W), np.uint8)
    shape[4:12, 5:15] = 1
    binary = str(tmp_path / "01.png")
    iio.imwrite(binary, shape)  # 0/1 in 8 bits: the object is 1
    assert np.array_equal(read_mask(binary, "white"), shape == 1)
    assert np.array_equal(read_mask(binary, "nonzero"), shape == 1)
    iio.imwrite(tmp_path / "0255.png", shape * 255)
    assert np.array_equal(read_mask(str(tmp_path / "0255.png"), "white"), shape == 1)
    iio.imwrite(tmp_path / "16.png", shape.astype(np.uint16))
    assert np.array_equal(read_mask(str(tmp_path / "16.png"), "white"), shape == 1)
    cover = str(tmp_path / "cover.exr")
    write_exr(cover, {"Y": np.where(shape, 0.75, 0.3)})
    assert np.array_equal(read_mask(cover, "white"), shape == 1)  # coverage of at least a half
    write_exr(cover, {"Y": np.full((H, W), 0.3)})
    with pytest.raises(DatasetError, match=f"^{cover}: the mask's largest value is 0.3 of its range 1: no pixel"):
        read_mask(cover, "white")


@pytest.mark.parametrize("rule", ["white", "nonzero"])
def test_a_jpeg_mask_does_not_grow(tmp_path, rule):
    """JPEG's ringing leaves small values around the object: thresholded at half the range, the mask
    keeps the drawn one's size (SPIn-NeRF's 'nonzero' labels too)."""
    shape = np.zeros((48, 64), np.uint8)
    shape[10:30, 12:40] = 255
    shape[30:38, 20:30] = 255
    iio.imwrite(tmp_path / "m.jpg", shape, quality=75)
    got = read_mask(str(tmp_path / "m.jpg"), rule)
    assert abs(int(got.sum()) - int((shape > 0).sum())) <= 0.03 * (shape > 0).sum()
    assert (np.asarray(iio.imread(tmp_path / "m.jpg")) > 0).sum() > 1.1 * (shape > 0).sum()  # what 'nonzero' gave


# ------------------------------------------------------------------------------------- rigs and splits
def test_cameras_at_one_point_are_noted_and_refused_for_a_fit_and_twin_poses_noted(tmp_path):
    root = str(tmp_path)
    meta, names = transforms(root)
    for frame in meta["frames"]:  # turned about one point: a panorama, no depth
        frame["transform_matrix"] = [row[:3] + [1.0 if i == 0 else 0.0] for i, row in
                                     enumerate(frame["transform_matrix"][:3])] + [[0, 0, 0, 1]]
    write_json(root, meta)
    ds = load_dataset(root)  # read all the same (its views may be rendered), noted, and refused by a fit
    line = f"{root}/transforms.json: all 4 cameras stand at one point (1, 0, 0): views from one point show no depth"
    assert any(n.startswith(line) for n in ds.meta["notes"])
    with pytest.raises(DatasetError, match=f"^{re.escape(line)}"):
        check_rig(ds)
    for frame in meta["frames"]:
        frame["transform_matrix"] = meta["frames"][0]["transform_matrix"]
    write_json(root, meta)
    with pytest.raises(DatasetError, match="transforms.json: all 4 cameras have one pose"):
        check_rig(load_dataset(root))
    meta, names = transforms(root)
    meta["frames"][2]["transform_matrix"] = meta["frames"][0]["transform_matrix"]
    write_json(root, meta)
    ds = load_dataset(root)
    assert "1 views have the pose of an earlier view ('img_02.png' = 'img_00.png')" in " ".join(ds.meta["notes"])
    check_rig(ds)


def test_holdout_on_a_dataset_with_its_own_split_is_noted_and_too_large_a_one_refused(tmp_path):
    root = str(tmp_path)
    meta, _ = transforms(root)
    with pytest.raises(DatasetError, match=f"^{root}: holdout 5 is more than the 4 views"):
        load_dataset(root, holdout=5)
    assert list(load_dataset(root).split) == ["test", "train", "train", "train"]  # the default 8 on 4 views
    assert list(load_dataset(root, holdout=4).split) == ["test", "train", "train", "train"]
    for k, frame in enumerate(meta["frames"]):
        frame["split"] = "test" if k == 3 else "train"
    write_json(root, meta)
    for holdout in (2, 1000):
        ds = load_dataset(root, holdout=holdout)
        assert list(ds.split) == ["train"] * 3 + ["test"]
        assert (f"holdout {holdout} is ignored: the split comes from the frames' 'split' keys in "
                f"{root}/transforms.json") in ds.meta["notes"]
    assert not any("holdout" in n for n in load_dataset(root).meta["notes"])  # the default is no choice


def test_a_view_in_both_label_and_test_label_is_a_test_view_and_noted(tmp_path):
    cams = [Camera(look_at([0.1 * k, 0.0, -3.0], [0.0, 0.0, 0.0]), 50.0, W, H) for k in range(4)]
    write_llff(str(tmp_path), cams, [(1.0, 5.0)] * 4)
    for sub in ("images", "images/label", "images/test_label"):
        os.makedirs(tmp_path / sub)
    m = np.zeros((H, W), np.uint8)
    m[4:9, 4:9] = 1
    for k in range(4):
        iio.imwrite(tmp_path / "images" / f"{k}.png", np.full((H, W, 3), 40 * k, np.uint8))
        iio.imwrite(tmp_path / "images" / "label" / f"{k}.png", m)
    iio.imwrite(tmp_path / "images" / "test_label" / "0.png", m)
    ds = load_dataset(str(tmp_path))
    assert list(ds.split) == ["test", "train", "train", "train"]
    assert any(n.startswith("1 views have a mask in both label/ and test_label/ (the first: 0.png): they are test "
                            "views") for n in ds.meta["notes"])


# ------------------------------------------------------------------------------------- fields of transforms.json
@pytest.mark.parametrize("change, message", [
    (lambda m: m.update(w="512"), "'w' must be a finite number, got \"512\""),
    (lambda m: m.update(fl_x=None), "'fl_x' must be a finite number, got null"),
    (lambda m: m["frames"][1].update(h=[18]), "frame 'h' must be a finite number, got [18]"),
    (lambda m: m.update(applied_transform=[[1, 0], [0, 1]]), "'applied_transform' must be a 3x4 or 4x4 matrix of "
                                                             "finite numbers, got 2x2"),
    (lambda m: m.update(applied_scale=0), "'applied_scale' must be > 0, got 0.0"),
    (lambda m: m.update(moved_transform="eye"), "'moved_transform' must be a 4x4 matrix of finite numbers, got "
                                                "non-numeric"),
    (lambda m: m.update(background_color=[1, 1]), "'background_color' must be a list of 3 finite numbers, got 2"),
    (lambda m: m.update(aabb=[[1, 1, 1], [0, 0, 0]]), "'aabb' must be [[x0, y0, z0], [x1, y1, z1]] with x1 > x0"),
    (lambda m: m.update(aabb=[[0, 0], [1, 1]]), "'aabb' must be a 2x3 matrix of finite numbers, got 2x2"),
    (lambda m: m.update(near="1"), "'near' must be a finite number, got \"1\""),
    (lambda m: m.update(forward_facing="yes"), "'forward_facing' must be true or false, got \"yes\""),
    (lambda m: m["frames"][2].update(file_path=3), "frame 2: 'file_path' must be a file path, got 3"),
    (lambda m: m["frames"][2].update(transform_matrix=[[1, 0, 0]]),
     "frame 2 (img_02.png): 'transform_matrix' must be a 4x4 or 3x4 matrix of finite numbers, got 1x3"),
    (lambda m: m["frames"].__setitem__(1, "img_01"), "frame 1 must be an object"),
])
def test_every_field_of_transforms_json_is_checked_and_named(tmp_path, change, message):
    root = str(tmp_path)
    meta, _ = transforms(root)
    change(meta)
    write_json(root, meta)
    with pytest.raises(DatasetError) as err:
        load_dataset(root)
    assert str(err.value).startswith(f"{root}/transforms.json: ") and message in str(err.value), err.value


def test_a_latin1_transforms_json_is_named(tmp_path):
    root = str(tmp_path)
    meta, _ = transforms(root)
    meta["comment"] = "caméra"
    (tmp_path / "transforms.json").write_bytes(json.dumps(meta, ensure_ascii=False).encode("latin-1"))
    with pytest.raises(DatasetError, match=f"^{root}/transforms.json: not UTF-8 text, as JSON must be .byte "):
        load_dataset(root)


# ------------------------------------------------------------------------------------- the object's hull, up front
def test_an_empty_object_hull_is_refused_before_the_fit(tmp_path):
    """check_hull (called at the fit's start): masks only on test views, or masks that no point of the
    scene box projects into from the training views, are refused in one line naming the dataset."""
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.fields import FitInputs
    from mi_voldis.fit.hull import check_hull
    root = str(tmp_path)
    meta, names = transforms(root, n=6)
    for name in names:  # every view sees the origin at its centre
        m = np.zeros((H, W), np.uint8)
        m[6:12, 8:16] = 255
        iio.imwrite(os.path.join(root, "masks", name), m)
    cfg = FitConfig.from_sources(None, [])
    inputs = lambda: FitInputs.of(load_dataset(root, holdout=3), cfg, str(tmp_path / "ck.npz"), False)  # noqa: E731
    check_hull(inputs())
    for k, name in enumerate(names):  # object masks only on the test views (0 and 3)
        if k % 3:
            os.remove(os.path.join(root, "masks", name))
    with pytest.raises(DatasetError, match=f"^{root}: no training view has an object mask .4 training views, 2 masked "
                                           "test views.: the object's hull"):
        check_hull(inputs())
    for k, name in enumerate(names):  # masks in corners that no common point reaches
        m = np.zeros((H, W), np.uint8)
        if k % 2:
            m[:3, :3] = 255
        else:
            m[-3:, -3:] = 255
        iio.imwrite(os.path.join(root, "masks", name), m)
    with pytest.raises(DatasetError, match=f"^{root}: the object's visual hull is empty: no point of the scene box"):
        check_hull(inputs())
    # train.py stops there, before its first step: one line, no run, no checkpoint left to resume
    import subprocess
    import sys
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "train.py"), root, "--out", str(out),
                           "--holdout", "3", "--quiet"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 1 and done.stderr.strip().splitlines() == [
        f"error: {root}: the object's visual hull is empty: no point of the scene box projects inside the object "
        "masks of enough of the 4 masked training views that see it (hull_min_views 0.9); the masks, poses or "
        "intrinsics disagree"], done.stderr
    assert not out.exists() and not os.path.exists(str(out) + ".partial")


# ------------------------------------------------------------------------------------- make_masks' given masks
def test_make_masks_refuses_what_is_not_a_mask_of_this_dataset(tiny_dataset, tiny_run, tmp_path, capsys):
    """An all-white mask, a photo (colour or grey), the same view twice, a run of another dataset: one line
    naming the file or flag, before anything is fitted or written."""
    import shutil

    from test_bad_inputs import _boundary, script, tree_digest
    names = sorted(os.listdir(os.path.join(tiny_dataset, "images")))
    photo = os.path.join(tiny_dataset, "images", names[0])
    mask = os.path.join(tiny_dataset, "masks", os.path.splitext(names[0])[0] + ".png")
    white, grey = str(tmp_path / "white.png"), str(tmp_path / "grey.png")
    iio.imwrite(white, np.full(iio.imread(mask).shape[:2], 255, np.uint8))
    iio.imwrite(grey, np.round(iio.imread(photo)[..., :3].mean(axis=2)).astype(np.uint8))
    other = str(tmp_path / "other")
    shutil.copytree(tiny_dataset, other)
    out = str(tmp_path / "masks")
    before = [tree_digest(tiny_dataset), tree_digest(tiny_run)]
    for args, message in [
        (["--from-views", f"1={white}"], f"{white}: the mask covers every pixel"),
        (["--from-views", f"1={photo}"], f"{photo}: a colour image, not a mask"),
        (["--from-views", f"1={grey}"], f"{grey}: not a mask: "),
        (["--from-views", f"1={mask}", f"{os.path.splitext(names[1])[0]}={mask}"],
         f"{mask}: view {names[1]} is given twice ({mask} and {mask})"),
        (["--from-views", f"1={mask}", f"1={white}"], f"--from-views: view '1' is given twice ({mask} and {white})"),
    ]:
        assert _boundary.run(script("make_masks").main, [tiny_dataset, "--out", out, "--run", tiny_run, *args]) == 1
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("error: ") and message in err, err
    assert _boundary.run(script("make_masks").main, [other, "--out", out, "--run", tiny_run, "--from-views",
                                                     f"1={mask}"]) == 1
    assert f"{tiny_run}: the run was fitted on {tiny_dataset}, not on {other}" in capsys.readouterr().err
    assert not os.path.exists(out) and before == [tree_digest(tiny_dataset), tree_digest(tiny_run)]


# ------------------------------------------------------------------------------------- the error boundary
def test_the_boundary_keeps_the_reason_dr_jit_puts_above_and_numpy_warnings_off_stderr(capsys):
    import warnings

    import drjit as dr

    from voldis_cli import boundary

    def drjit_fails(argv):
        dr.mean(object())

    assert boundary.run(drjit_fails, []) == 1
    err = capsys.readouterr().err
    assert err.startswith("error: dr.mean(): encountered an exception: drjit.sum(<object>): the input must be"), err
    assert "see above" not in err and err.count("\n") == 1

    def numpy_warns_then_fails(argv):
        np.mean(np.zeros(0))
        raise ValueError("grid.npz: empty")

    assert boundary.run(numpy_warns_then_fails, []) == 1
    assert capsys.readouterr().err == ("error: grid.npz: empty (after RuntimeWarning: Mean of empty slice; "
                                       "RuntimeWarning: invalid value encountered in scalar divide)\n")

    def numpy_warns(argv):
        np.float32(1) / np.float32(0)
        warnings.warn("a library's word")

    assert boundary.run(numpy_warns, []) == 0
    assert capsys.readouterr().err == "warning: UserWarning: a library's word\n"


# ------------------------------------------------------------------------------------- camera_path.json
@pytest.mark.parametrize("change, message", [
    (lambda d, p: d.pop("camera_path"), "{path}: not a nerfstudio camera path"),
    (lambda d, p: d.update(camera_path=[]), "{path}: 'camera_path' must be a non-empty list of cameras, got []"),
    (lambda d, p: d.update(render_width="512"), "{path}: 'render_width' must be a positive whole number, got \"512\""),
    (lambda d, p: d.update(render_height=0), "{path}: 'render_height' must be a positive whole number, got 0"),
    (lambda d, p: d["camera_path"][1].update(camera_to_world=[float("nan")] * 16),
     "{path}: 'camera_path[1].camera_to_world' must be 16 numbers or 4x4, all finite; got non-finite numbers"),
    (lambda d, p: d["camera_path"][0].update(camera_to_world=[1, 0, 0]),
     "{path}: 'camera_path[0].camera_to_world' must be 16 numbers or 4x4, all finite; got shape (3,)"),
    (lambda d, p: d["camera_path"][0].update(fov=180),
     "{path}: camera_path[0].fov must be a vertical field of view in"),
    (lambda d, p: p.update(scale=0), "{dp}: 'scale' must be a positive number, got 0"),
    (lambda d, p: p.update(transform=[[1, 0], [0, 1]]), "{dp}: 'transform' must be 3x4 or 4x4, all finite; got shape"),
    (lambda d, p: p.update(transform=[[0, 0, 0, 0]] * 3), "{dp}: 'transform' is singular"),
])
def test_a_camera_path_is_checked_field_by_field(tmp_path, change, message):
    from mi_voldis.camera_paths import read_nerfstudio_path
    eye = np.eye(4).ravel().tolist()
    data = {"render_width": 40, "render_height": 30, "camera_path": [{"camera_to_world": eye, "fov": 50}] * 2}
    data["camera_path"] = [dict(e) for e in data["camera_path"]]
    dp = {"transform": np.eye(4)[:3].tolist(), "scale": 0.5}
    change(data, dp)
    path, dpath = tmp_path / "camera_path.json", tmp_path / "dataparser_transforms.json"
    path.write_text(json.dumps(data))
    dpath.write_text(json.dumps(dp))
    with pytest.raises(ValueError) as err:
        read_nerfstudio_path(str(path), str(dpath))
    assert str(err.value).startswith(message.format(path=path, dp=dpath)), err.value


@pytest.mark.parametrize("lo,hi,shown", [((1, 0, 0), (-1, 1, 1), "min [1, 0, 0] and max [-1, 1, 1]"),
                                         ((0, 0, 0), (1, 0, 1), "min [0, 0, 0] and max [1, 0, 1]")])
def test_a_grid_file_with_an_inverted_or_flat_box_is_refused_naming_it(tmp_path, lo, hi, shown):
    """The box in a .vol header places the field when the scene gives no to_world: an inverted one would
    mirror it, a flat one collapse it, without a word."""
    import mitsuba as mi

    from mi_voldis.io.vol import write_vol
    for key, channels in (("density", 1), ("color", 3)):
        write_vol(tmp_path / f"{key}.vol", np.zeros((2, 2, 2, channels)), lo, hi)
    with pytest.raises(RuntimeError) as e:
        mi.load_dict({"type": "radiance_field", "density": str(tmp_path / "density.vol"),
                      "color": str(tmp_path / "color.vol")})
    assert f"{tmp_path / 'density.vol'}: the grid's box needs min < max on every axis, got {shown}" in str(e.value)


def test_spread_picks_views_evenly_from_first_to_last():
    from mi_voldis.data.types import spread
    assert spread(10, 3).tolist() == [0, 4, 9]  # (n - 1) / (count - 1) = 4.5 apart, rounded
    assert spread(24, 8).tolist() == [0, 3, 7, 10, 13, 16, 20, 23]
    assert spread(3, 10).tolist() == [0, 1, 2]  # all of them when fewer than asked
    assert spread(5, 1).tolist() == [0] and spread(5, 0).tolist() == []
