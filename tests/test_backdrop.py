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
