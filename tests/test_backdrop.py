"""Datasets composited over a background colour (Blender's RGBA layout): renders are compared with the
photographs, and previewed, over that colour, as training compares them."""
import json
import os

import imageio.v3 as iio
import numpy as np

from mi_voldis.cameras import Camera
from mi_voldis.data import load_dataset
from mi_voldis.data.conventions import mitsuba_to_opengl
from mi_voldis.export import previews
from mi_voldis.io.images import linear_to_uint8
from mi_voldis.synth.rigs import look_at

H, W = 24, 32
BACKDROP = [0.2, 0.6, 0.9]


def empty_rgba_capture(root, n=9):
    """``n`` views around the origin of next to nothing: RGBA PNGs with alpha 1/255 everywhere (a random
    colour under it; alpha 0 would hold no picture at all), over ``BACKDROP``."""
    rng = np.random.default_rng(3)
    os.makedirs(os.path.join(root, "images"))
    frames = []
    for k in range(n):
        cam = Camera(look_at([3 * np.sin(k), 0.6, 3 * np.cos(k)], [0, 0, 0]), 40.0, W, H)
        rgba = np.concatenate([rng.integers(0, 255, (H, W, 3)), np.ones((H, W, 1))], -1).astype(np.uint8)
        iio.imwrite(os.path.join(root, "images", f"r_{k}.png"), rgba)
        frames.append({"file_path": f"images/r_{k}", "transform_matrix": mitsuba_to_opengl(cam.to_world).tolist()})
    meta = {"fl_x": cam.focal, "w": W, "h": H, "aabb": [[-1, -1, -1], [1, 1, 1]], "background_color": BACKDROP,
            "frames": frames}
    with open(os.path.join(root, "transforms.json"), "w") as f:
        json.dump(meta, f)
    return root


def test_a_layer_as_photographed_is_over_the_datasets_backdrop(tmp_path):
    ds = load_dataset(empty_rgba_capture(str(tmp_path / "empty")))
    rgb = np.zeros((2, 1, 3), np.float32)
    rgb[1, 0] = [0.5, 0.25, 0.0]
    alpha = np.array([[0.0], [0.5]], np.float32)
    shown = ds.as_photographed((rgb, alpha, None))
    np.testing.assert_allclose(shown[0, 0], BACKDROP, atol=1e-6)  # nothing there: the backdrop
    np.testing.assert_allclose(shown[1, 0], [0.6, 0.55, 0.45], atol=1e-6)  # C + (1 - A) backdrop
    np.testing.assert_allclose(ds.images[0], np.broadcast_to(BACKDROP, (H, W, 3)), atol=2 / 255)
    ds.meta.pop("background_color")  # a capture: every ray ends on something, the RGB is what it shows
    assert ds.as_photographed((rgb, alpha, None)) is rgb


def test_previews_over_a_backdrop_show_it_where_the_layer_is_clear():
    linear = {c: np.zeros((1, 2), np.float32) for c in ("R", "G", "B", "A", "depth.Z")}
    linear["R"][0, 1], linear["A"][0, 1] = 1.0, 1.0  # one opaque red pixel, one empty one
    over_black = previews(linear, (), None)["composite"]
    over = previews(linear, (), BACKDROP)["composite"]
    assert over_black[0, 0].tolist() == [0, 0, 0] and over_black[0, 1].tolist() == [255, 0, 0]
    assert over[0, 0].tolist() == linear_to_uint8(np.array(BACKDROP, np.float32)).tolist()
    assert over[0, 1].tolist() == [255, 0, 0]


def test_a_fit_of_a_capture_on_a_backdrop_is_scored_and_previewed_over_it(tmp_path):
    """An empty scene photographed over a colour: fitted, it is that colour in every held-out view (its
    PSNR high, not the backdrop's distance from black), and so are its previews."""
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.run import run_fit
    data = empty_rgba_capture(str(tmp_path / "empty"))
    sets = ["steps_full=30", "calibration_steps=10", "coarse_resolution=8", "batch_rays=256", "steps_bg=2",
            "sh_degree=0", "eval_every=15", "occupancy_at_step=0", "resolution_schedule=[[0,8]]"]
    out = str(tmp_path / "run")
    run_fit(data, out, FitConfig.from_sources(None, sets), progress=False)
    metrics = json.load(open(os.path.join(out, "metrics.json")))
    assert metrics["held_out"]["psnr"] > 30, metrics["held_out"]
    log = json.load(open(os.path.join(out, "log.json")))
    assert [r["test_psnr"] for r in log if "test_psnr" in r][-1] > 30
    preview = iio.imread(os.path.join(out, "previews", "view000_full.png"))[..., :3].astype(int)
    expected = linear_to_uint8(np.array(BACKDROP, np.float32)).astype(int)
    assert np.abs(preview - expected).max() <= 3


def sphere_alpha(cam, centre, radius):
    """Alpha of a sphere seen by ``cam``: 1 at the pixels whose central ray meets it, else 0."""
    from mi_voldis.cameras import pixel_rays
    px, py = np.meshgrid(np.arange(cam.width) + 0.5, np.arange(cam.height) + 0.5)
    o, d = pixel_rays(cam, px.ravel(), py.ravel())
    t = np.sum((np.asarray(centre) - o) * d, axis=1)
    miss = np.linalg.norm(o + t[:, None] * d - centre, axis=1)
    return ((miss <= radius) & (t > 0)).reshape(cam.height, cam.width).astype(np.float32)


def ring(n=12, distance=4.0, target=(0.0, 0.0, 0.0), width=64, height=48):
    return [Camera(look_at([distance * np.sin(2 * np.pi * k / n) + target[0], 1.0 + 0.5 * (k % 2),
                            distance * np.cos(2 * np.pi * k / n) + target[2]], list(target)), 40.0, width, height)
            for k in range(n)]


def test_the_silhouette_box_holds_the_object_and_little_more():
    """A sphere of radius 0.5 off the ring's centre, seen by 12 views: the visual hull of its silhouettes
    holds it, within its margin of lattice cells and the hull's excess of it."""
    from mi_voldis.data.scene_box import SILHOUETTE_LATTICE, SILHOUETTE_MARGIN, silhouette_box, world_box
    centre, radius = np.array([0.2, 0.1, -0.15]), 0.5
    cams = ring()
    box = world_box(cams)
    found = silhouette_box(cams, [sphere_alpha(c, centre, radius) for c in cams], box)
    cell = (box.hi - box.lo) / (SILHOUETTE_LATTICE - 1)
    assert found.kind == "world"
    assert np.all(found.lo <= centre - radius + 1e-9) and np.all(found.hi >= centre + radius - 1e-9)
    slack = 1.3 * radius + (SILHOUETTE_MARGIN + 1) * cell
    assert np.all(found.lo >= centre - slack) and np.all(found.hi <= centre + slack)
    assert np.prod(found.hi - found.lo) < 0.1 * np.prod(box.hi - box.lo)


def test_no_silhouette_box_where_the_hull_is_empty_or_reaches_the_layouts_box():
    from mi_voldis.data.scene_box import silhouette_box, world_box
    cams = ring()
    box = world_box(cams)
    full = [np.ones((c.height, c.width), np.float32) for c in cams]
    assert silhouette_box(cams, full, box) is None  # covered everywhere: the object may go on beyond the box
    empty = [np.zeros((c.height, c.width), np.float32) for c in cams]
    assert silhouette_box(cams, empty, box) is None
    # silhouettes of two different spheres: views that disagree leave no point
    apart = [sphere_alpha(c, (1.0, 0, 0) if k % 2 else (-1.0, 0, 0), 0.2) for k, c in enumerate(cams)]
    assert silhouette_box(cams, apart, box) is None


def test_an_rgba_capture_of_an_object_fits_in_the_box_of_its_silhouettes(tmp_path):
    """transforms.json with RGBA views of a sphere and no aabb: the loader carves the box from the
    training views' alpha, says so, and 'auto' space fits in it; with an aabb the stated box stays."""
    from mi_voldis.data.scene_box import fitting_box
    root = tmp_path / "sphere"
    os.makedirs(root / "images")
    centre, radius = np.array([0.1, 0.0, 0.0]), 0.4
    cams = ring(n=9, width=W, height=H)
    frames = []
    for k, cam in enumerate(cams):
        alpha = sphere_alpha(cam, centre, radius)
        rgba = np.concatenate([np.full((H, W, 3), 200.0), 255 * alpha[..., None]], -1).astype(np.uint8)
        iio.imwrite(root / "images" / f"r_{k}.png", rgba)
        frames.append({"file_path": f"images/r_{k}", "transform_matrix": mitsuba_to_opengl(cam.to_world).tolist()})
    meta = {"fl_x": cams[0].focal, "w": W, "h": H, "frames": frames}
    with open(root / "transforms.json", "w") as f:
        json.dump(meta, f)
    ds = load_dataset(str(root))
    assert ds.meta["silhouette_box"] and fitting_box(ds).kind == "world"
    assert np.all(ds.box.lo <= centre - radius) and np.all(ds.box.hi >= centre + radius)
    assert np.all(ds.box.hi - ds.box.lo < 4 * radius)
    assert any("scene box from the training views' alpha" in n for n in ds.meta["notes"])
    for k in range(len(cams)):  # alpha everywhere: the hull fills the cameras' box, no box is carved, and it says so
        iio.imwrite(root / "images" / f"r_{k}.png", np.full((H, W, 4), 200, np.uint8))
    ds = load_dataset(str(root))
    assert "silhouette_box" not in ds.meta and fitting_box(ds).kind == "contract"
    assert any("no scene box from the training views' alpha" in n for n in ds.meta["notes"])
    meta["aabb"] = [[-2, -2, -2], [2, 2, 2]]
    with open(root / "transforms.json", "w") as f:
        json.dump(meta, f)
    ds = load_dataset(str(root))
    assert "silhouette_box" not in ds.meta and ds.box.lo.tolist() == [-2, -2, -2]
