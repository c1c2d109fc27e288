"""Dataset loaders, camera conventions, scene spaces and the bundled synthetic scenes."""
import json
import os

import imageio.v3 as iio
import mitsuba as mi
import numpy as np
import pytest
from helpers import random_field

from mi_voldis.cameras import Camera, pixel_rays
from mi_voldis.data import DatasetError, load_dataset
from mi_voldis.data.conventions import mitsuba_to_opengl
from mi_voldis.data.llff import write_llff
from mi_voldis.space import SceneSpace
from mi_voldis.synth.rigs import look_at

# the real captures: $MI_VOLDIS_CAPTURES, else ../shared/data beside the checkout (as scripts/bench.py)
SHARED = os.environ.get("MI_VOLDIS_CAPTURES") or os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def camera(principal=(0.0, 0.0), width=24, height=18):
    return Camera(look_at([0.4, 0.3, -3.0], [0.0, 0.1, 0.0]), 50.0, width, height, principal)


@pytest.mark.parametrize("principal", [(0.0, 0.0), (0.1, -0.05)])
def test_pixel_rays_match_mitsuba_sensor(principal):
    cam = camera(principal)
    sensor = mi.load_dict(cam.sensor_dict())
    px, py = np.array([0.5, 3.5, 23.5, 11.0]), np.array([0.5, 17.5, 2.0, 9.0])
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(px / cam.width, py / cam.height), mi.Point2f(0.5))
    o, d = pixel_rays(cam, px, py)
    np.testing.assert_allclose(np.array(ray.d).T, d, atol=1e-6)
    # Mitsuba starts rays on the near clip plane, along the same line through the camera centre
    np.testing.assert_allclose(np.cross(np.array(ray.o).T - o, d), 0.0, atol=1e-6)


def render_with(cam):
    scene = mi.load_dict({"type": "scene", "sensor": cam.sensor_dict(),
                          "integrator": {"type": "voldis", "samples": 16, "full": random_field(1),
                                         "bg": random_field(2)}})
    return np.array(mi.render(scene, seed=3))


def write_images(folder, n, h, w, seed=0):
    os.makedirs(folder, exist_ok=True)
    rng = np.random.default_rng(seed)
    names = []
    for k in range(n):
        names.append(f"img_{k:02d}.png")
        iio.imwrite(os.path.join(folder, names[-1]), rng.integers(0, 255, (h, w, 3), dtype=np.uint8))
    return names


def write_transforms(root, cams, names, **top):
    frames = [{"file_path": f"images/{os.path.splitext(n)[0]}",
               "transform_matrix": mitsuba_to_opengl(c.to_world).tolist()}
              for c, n in zip(cams, names)]
    cam = cams[0]
    meta = {"fl_x": cam.focal, "fl_y": cam.focal, "cx": cam.width * (0.5 - cam.principal[0]),
            "cy": cam.height * (0.5 - cam.principal[1]), "w": cam.width, "h": cam.height, "frames": frames,
            "aabb": [[-1, -1, -1], [1, 1, 1]], **top}
    with open(os.path.join(root, "transforms.json"), "w") as f:
        json.dump(meta, f)
    return meta


def test_sensor_round_trips_through_both_formats(tmp_path):
    """A Mitsuba sensor written as transforms.json and as poses_bounds.npy, read back, renders the
    identical image."""
    cams = [camera((0.07, -0.04)), camera()]
    names = write_images(str(tmp_path / "t" / "images"), 2, 18, 24)
    write_transforms(str(tmp_path / "t"), cams, names, forward_facing=False)
    back = load_dataset(str(tmp_path / "t"))
    assert back.meta["format"] == "transforms"
    np.testing.assert_array_equal(render_with(back.cameras[0]), render_with(cams[0]))

    llff_cams = [camera(), Camera(look_at([0.5, 0.2, -3.0], [0.0, 0.0, 0.0]), 50.0, 24, 18)]
    write_images(str(tmp_path / "l" / "images"), 2, 18, 24)
    write_llff(str(tmp_path / "l"), llff_cams, [(1.0, 5.0)] * 2)
    back = load_dataset(str(tmp_path / "l"))
    assert back.meta["format"] == "llff"
    for a, b in zip(back.cameras, llff_cams):
        np.testing.assert_allclose(a.to_world, b.to_world, atol=1e-12)
        assert abs(a.fov_x - b.fov_x) < 1e-9
    np.testing.assert_allclose(render_with(back.cameras[1]), render_with(llff_cams[1]), atol=1e-6)


def test_llff_focal_is_rescaled_to_the_images_read(tmp_path):
    """Poses written for 48x36 images, images stored at half size in images_2/."""
    cams = [Camera(look_at([0.1 * k, 0.0, -3.0], [0.0, 0.0, 0.0]), 50.0, 48, 36) for k in range(3)]
    write_llff(str(tmp_path), cams, [(1.0, 5.0)] * 3)
    write_images(str(tmp_path / "images_2"), 3, 18, 24)
    ds = load_dataset(str(tmp_path))
    assert ds.size == (18, 24)
    assert abs(ds.cameras[0].focal - cams[0].focal / 2) < 1e-9
    assert abs(ds.cameras[0].fov_x - 50.0) < 1e-9
    assert list(ds.split) == ["test", "train", "train"]
    assert ds.box.kind == "ndc" and ds.box.ndc_near == pytest.approx(0.75)


def test_the_fit_space_follows_the_cameras(tmp_path):
    """'auto': a capture without a stated box is fitted in contracted space, forward-facing or not (its NDC
    box on request), one with an aabb in its box."""
    from mi_voldis.data.scene_box import fitting_box
    cams = [Camera(look_at([0.1 * k, 0.0, -3.0], [0.0, 0.0, 0.0]), 50.0, 48, 36) for k in range(3)]
    write_images(str(tmp_path / "ff" / "images"), 3, 36, 48)
    write_llff(str(tmp_path / "ff"), cams, [(1.0, 5.0)] * 3)
    forward = load_dataset(str(tmp_path / "ff"))
    assert forward.box.kind == "ndc"  # what the loader offers
    assert fitting_box(forward, "auto").kind == "contract" and fitting_box(forward, "ndc").kind == "ndc"
    orbit = [camera()] + [Camera(look_at([3 * np.sin(a), 0.5, -3 * np.cos(a)], [0.0, 0.0, 0.0]), 50.0, 24, 18)
                          for a in (1.5, 3.0, 4.5)]
    names = write_images(str(tmp_path / "o" / "images"), 4, 18, 24)
    meta = write_transforms(str(tmp_path / "o"), orbit, names, forward_facing=False)
    assert fitting_box(load_dataset(str(tmp_path / "o")), "auto").kind == "world"  # its aabb
    del meta["aabb"]
    with open(tmp_path / "o" / "transforms.json", "w") as f:
        json.dump(meta, f)
    orbit_ds = load_dataset(str(tmp_path / "o"))
    assert fitting_box(orbit_ds, "auto").kind == "contract"
    # contract_radius scales a 360-degree capture's linear cube, not a forward-facing one's
    full, half = fitting_box(orbit_ds, "auto"), fitting_box(orbit_ds, "auto", radius_scale=0.5)
    np.testing.assert_allclose(half.to_world[:3, :3], 0.5 * full.to_world[:3, :3])
    np.testing.assert_allclose(half.to_world[:3, 3], full.to_world[:3, 3])
    np.testing.assert_allclose(fitting_box(forward, "auto", radius_scale=0.5).to_world,
                               fitting_box(forward, "auto").to_world)


def test_ndc_space_maps_rays_to_lines():
    cams = [Camera(look_at([0.1 * k, 0.05 * k, -3.0], [0.0, 0.0, 0.0]), 50.0, 24, 18) for k in range(4)]
    from mi_voldis.data.scene_box import average_pose
    space = SceneSpace("ndc", average_pose(cams), 1.2, (2.1, 2.8))
    o, d = pixel_rays(cams[1], np.array([3.0, 20.0]), np.array([4.0, 15.0]))
    o_s, d_s, t_max = space.ray(mi.Point3f(*o.T), mi.Vector3f(*d.T))
    for t_ndc in (0.0, 0.3, 0.9):
        p = np.array(o_s + t_ndc * d_s).T
        world = space.to_world_np(p)
        # the point lies on the world ray, and maps back
        np.testing.assert_allclose(np.cross(world - o, d), 0.0, atol=1e-4)
        np.testing.assert_allclose(space.from_world_np(world), p, atol=1e-4)
    back = np.array(space.to_world(space.from_world(mi.Point3f(*(o + 2.5 * d).T)))).T
    np.testing.assert_allclose(back, o + 2.5 * d, atol=1e-5)


def test_forward_facing_render_in_ndc_is_analytic():
    """A homogeneous NDC slab z' in [-0.2, 0.4] of density sigma: alpha = 1 - exp(-sigma L') with L'
    the NDC length of the ray inside it (both fields fill the slab, so the samples cover it exactly)."""
    from mi_voldis.field.spec import box_transform, constant_field
    from mi_voldis.render.rays import render_rays
    cams = [Camera(look_at([0.1 * k, 0.0, -3.0], [0.0, 0.0, 0.0]), 50.0, 24, 18) for k in range(3)]
    from mi_voldis.data.scene_box import average_pose
    ref = average_pose(cams)
    props = SceneSpace("ndc", ref, 1.0, (2.0, 2.5)).integrator_properties()
    integ = mi.load_dict({"type": "voldis", "samples": 64, "mode": "full",
                          "full": constant_field(0.8, [0.2, 0.5, 0.9], box_transform([-3, -3, -0.2], [3, 3, 0.4])),
                          "bg": constant_field(1e-9, [0, 0, 0], box_transform([-3, -3, -0.2], [3, 3, 0.4])),
                          **props})
    o, d = pixel_rays(cams[1], np.array([2.0, 12.0, 20.0]), np.array([3.0, 9.0, 15.0]))
    o, d = mi.Point3f(*o.T), mi.Vector3f(*d.T)
    out = render_rays(integ, o, d, mi.Float(0.3, 0.6, 0.9), layers=("full",))
    _, d_s, _ = integ.space.ray(o, d)
    length = 0.6 / np.array(d_s.z) * np.linalg.norm(np.array(d_s), axis=0)
    np.testing.assert_allclose(np.array(out["full"][1]), -np.expm1(-0.8 * length), atol=2e-5)
    # depth is reported in world units: the expected distance lies where the slab is in the world
    z_world = [space_distance(integ.space, o, d, zp) for zp in (-0.2, 0.4)]
    depth = np.array(out["full"][2])
    assert np.all((depth > z_world[0] - 1e-3) & (depth < z_world[1] + 1e-3))


def space_distance(space, o, d, z_ndc):
    o_s, d_s, _ = space.ray(o, d)
    t = (z_ndc - np.array(o_s.z)) / np.array(d_s.z)
    p = np.array(o_s).T + t[:, None] * np.array(d_s).T
    return np.linalg.norm(space.to_world_np(p) - np.array(o).T, axis=1)


# ------------------------------------------------------------------------------------- bad input
def good_transforms(root, n=3, masks=True):
    cams = [Camera(look_at([3 * np.sin(k), 0.5, 3 * np.cos(k)], [0, 0, 0]), 45.0, 24, 18) for k in range(n)]
    names = write_images(os.path.join(root, "images"), n, 18, 24)
    meta = write_transforms(root, cams, names)
    if masks:
        os.makedirs(os.path.join(root, "masks"), exist_ok=True)
        for k, name in enumerate(names):
            m = np.zeros((18, 24), np.uint8)
            m[5:10, 6 + k:12 + k] = 255
            iio.imwrite(os.path.join(root, "masks", name), m)
    return meta, names


def rewrite(root, meta):
    with open(os.path.join(root, "transforms.json"), "w") as f:
        json.dump(meta, f)


def test_good_transforms_load(tmp_path):
    good_transforms(str(tmp_path))
    ds = load_dataset(str(tmp_path))
    assert ds.masks.shape == (3, 18, 24) and ds.masks[1, 6, 7] and not ds.masks[1, 0, 0]


def test_effect_masks_load_outside_the_object_and_only_where_given(tmp_path):
    """``effect_mask_path`` (the object's shadow): read as white = effect, cleared inside the object's
    mask, nothing for a frame without one; a missing file or no object masks is named in one line."""
    root = str(tmp_path)
    meta, names = good_transforms(root)
    os.makedirs(tmp_path / "effects")
    for k in (0, 2):
        e = np.zeros((18, 24), np.uint8)
        e[8:14, 4:20] = 255  # overlaps the object's mask (rows 5-9)
        iio.imwrite(tmp_path / "effects" / names[k], e)
        meta["frames"][k]["effect_mask_path"] = f"effects/{names[k]}"
    rewrite(root, meta)
    ds = load_dataset(root)
    assert ds.effects.shape == (3, 18, 24) and not ds.effects[1].any()
    for k in (0, 2):
        assert not (ds.effects[k] & ds.masks[k]).any()
        assert ds.effects[k][10:14, 4:20].all() and ds.effects[k].sum() == 6 * 16 - ds.masks[k][8:14, 4:20].sum()
    meta["frames"][2]["effect_mask_path"] = "effects/none.png"
    rewrite(root, meta)
    with pytest.raises(DatasetError, match="effect mask 'effects/none.png' not found"):
        load_dataset(root)
    meta["frames"][2]["effect_mask_path"] = f"effects/{names[2]}"
    rewrite(root, meta)
    for n in names:
        os.remove(tmp_path / "masks" / n)
    with pytest.raises(DatasetError, match="effect masks but no object masks"):
        load_dataset(root)


def test_effect_masks_are_read_from_an_effects_folder_by_file_stem(tmp_path):
    """Without ``effect_mask_path``, ``effects/`` beside ``masks/`` (as for LLFF and COLMAP)."""
    root = str(tmp_path)
    _, names = good_transforms(root)
    os.makedirs(tmp_path / "effects")
    e = np.zeros((18, 24), np.uint8)
    e[12:16, 2:8] = 255
    iio.imwrite(tmp_path / "effects" / names[1], e)
    ds = load_dataset(root)
    assert ds.effects[1].sum() == 24 and not ds.effects[[0, 2]].any()
    llff = tmp_path / "llff"  # the same folders beside an LLFF capture
    cams = [Camera(look_at([0.1 * k, 0.0, -3.0], [0.0, 0.0, 0.0]), 50.0, 24, 18) for k in range(3)]
    llff.mkdir()
    write_llff(str(llff), cams, [(1.0, 5.0)] * 3)
    shot = write_images(str(llff / "images"), 3, 18, 24)
    for sub in ("masks", "effects"):
        os.makedirs(llff / sub)
        for k, name in enumerate(shot):
            iio.imwrite(llff / sub / name, iio.imread(tmp_path / sub / names[k]) if (tmp_path / sub / names[k]).exists()
                        else np.zeros((18, 24), np.uint8))
    assert np.array_equal(load_dataset(str(llff)).effects, ds.effects)


@pytest.mark.parametrize("breakage, message", [
    ("count", "2 poses but 3 images"),
    ("nan_pose", "non-finite pose"),
    ("skew_pose", "not a rigid rotation"),
    ("mixed_sizes", "all images of a set must have one size"),
    ("truncated", "unreadable or truncated image"),
])
def test_llff_errors(tmp_path, breakage, message):
    cams = [Camera(look_at([0.1 * k, 0.0, -3.0], [0.0, 0.0, 0.0]), 50.0, 24, 18) for k in range(3)]
    write_llff(str(tmp_path), cams, [(1.0, 5.0)] * 3)
    names = write_images(str(tmp_path / "images"), 3, 18, 24)
    pb = np.load(tmp_path / "poses_bounds.npy")
    culprit = "poses_bounds.npy"
    if breakage == "count":
        np.save(tmp_path / "poses_bounds.npy", pb[:2])
    elif breakage == "nan_pose":
        pb[1, 3] = np.nan
        np.save(tmp_path / "poses_bounds.npy", pb)
    elif breakage == "skew_pose":
        pb[2, 0] += 0.3  # shear the rotation
        np.save(tmp_path / "poses_bounds.npy", pb)
    elif breakage == "mixed_sizes":
        iio.imwrite(tmp_path / "images" / names[2], np.zeros((20, 24, 3), np.uint8))
        culprit = names[2]
    elif breakage == "truncated":
        data = (tmp_path / "images" / names[1]).read_bytes()
        (tmp_path / "images" / names[1]).write_bytes(data[: len(data) // 3])
        culprit = names[1]
    with pytest.raises(DatasetError, match=message) as err:
        load_dataset(str(tmp_path))
    assert culprit in str(err.value)


@pytest.mark.parametrize("breakage, message, culprit", [
    ("missing_mask_path", "mask .masks/img_01.png. not found", "transforms.json"),
    ("mask_size", "mask is 12x9 but the images are 24x18", "img_02"),
    ("empty_masks", "every object mask is empty", "masks"),
    ("full_mask", "mask covers every pixel", "img_00"),
    ("missing_ignore_mask", "mask_path 'masks/x.png' not found", "transforms.json"),
    ("ambiguous_focal", "intrinsics are ambiguous", "transforms.json"),
    ("bad_camera_model", "camera_model FOV cannot be undistorted", "transforms.json"),
    ("missing_image", "not found", "transforms.json"),
    ("bad_matrix", "not a rigid motion", "transforms.json"),
])
def test_transforms_errors(tmp_path, breakage, message, culprit):
    root = str(tmp_path)
    meta, names = good_transforms(root)
    masks = tmp_path / "masks"
    if breakage == "missing_mask_path":
        for k, frame in enumerate(meta["frames"]):
            frame["object_mask_path"] = f"masks/{names[k]}"
        os.remove(masks / names[1])
    elif breakage == "mask_size":
        iio.imwrite(masks / names[2], np.full((9, 12), 255, np.uint8))
    elif breakage == "empty_masks":
        for n in names:
            iio.imwrite(masks / n, np.zeros((18, 24), np.uint8))
    elif breakage == "full_mask":
        iio.imwrite(masks / names[0], np.full((18, 24), 255, np.uint8))
    elif breakage == "missing_ignore_mask":
        meta["frames"][1]["mask_path"] = "masks/x.png"
    elif breakage == "ambiguous_focal":
        meta["camera_angle_x"] = 1.0
    elif breakage == "bad_camera_model":
        meta["camera_model"] = "FOV"
    elif breakage == "missing_image":
        meta["frames"][2]["file_path"] = "images/nope"
    elif breakage == "bad_matrix":
        meta["frames"][1]["transform_matrix"][0][0] = 3.0
    rewrite(root, meta)
    with pytest.raises(DatasetError, match=message) as err:
        load_dataset(root)
    assert culprit in str(err.value)


# ------------------------------------------------------------------------------------- real data
@pytest.mark.skipif(not os.path.isdir(SHARED), reason=f"real captures not present at {SHARED} (set MI_VOLDIS_CAPTURES)")
@pytest.mark.parametrize("name, views, size, has_masks, kind", [
    ("fern", 20, (378, 504), False, "ndc"), ("statue", 29, (378, 504), True, "ndc"),
    ("lego_200", 200, (200, 200), False, "world")])
def test_real_captures_load(name, views, size, has_masks, kind):
    if not os.path.isdir(os.path.join(SHARED, name)):  # a folder of some captures (a GPU machine's copy)
        pytest.skip(f"capture {name} not present in {SHARED}")
    ds = load_dataset(os.path.join(SHARED, name))
    assert len(ds.images) == views and ds.size == size and ds.box.kind == kind
    assert (ds.masks is not None) == has_masks
    assert len(ds.test) > 0 and len(ds.train) >= len(ds.test)
    if name == "statue":  # poses are for 1008x756; images are 504x378
        raw = np.load(os.path.join(SHARED, name, "poses_bounds.npy"))
        assert abs(ds.cameras[0].focal - raw[0, 14] / 2) < 1e-6
        assert 0.01 < ds.masks.mean() < 0.5


# ------------------------------------------------------------------------------------- synthetic
@pytest.mark.parametrize("scene", ["tabletop", "room"])
def test_make_dataset_small(tmp_path, scene):
    from mi_voldis.synth.make import make_dataset
    out = str(tmp_path / scene)
    make_dataset(os.path.join(ROOT, "scenes", f"{scene}.xml"), out, views=9, resolution=(32, 24), spp=4,
                 progress=False)
    ds = load_dataset(out)
    assert ds.images.shape == (9, 24, 32, 3) and list(ds.test) == [0, 8]
    assert ds.box.kind == ("world" if scene == "tabletop" else "ndc")
    np.testing.assert_array_equal(ds.masks, ds.coverage > 0.5)
    assert np.all(np.isfinite(ds.backgrounds)) and np.isnan(ds.moved[1]).all() and np.isfinite(ds.moved[0]).all()
    # removing the object changes the pixels it covered
    diff = np.abs(ds.images - ds.backgrounds).max(axis=-1)
    assert diff[ds.masks].mean() > 2 * diff[~ds.masks].mean()  # (4 spp: the rest differs by noise)
    if scene == "room":
        assert os.path.isfile(os.path.join(out, "poses_bounds.npy"))
        llff = load_dataset(out, fmt="llff")
        for a, b in zip(llff.cameras, ds.cameras):
            np.testing.assert_allclose(a.to_world, b.to_world, atol=1e-9)
    else:  # deterministic for a seed
        again = str(tmp_path / "again")
        make_dataset(os.path.join(ROOT, "scenes", f"{scene}.xml"), again, views=9, resolution=(32, 24), spp=4,
                     progress=False)
        for sub in ("images", "masks", "backgrounds", "moved"):
            for f in sorted(os.listdir(os.path.join(out, sub))):
                assert (open(os.path.join(out, sub, f), "rb").read()
                        == open(os.path.join(again, sub, f), "rb").read()), f"{sub}/{f}"
