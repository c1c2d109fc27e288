"""The weight of a fitted run against a synthetic scene's true surfaces (mi_voldis.bench.geometry): the true
distance of each pixel, and the command's table and its refusals."""
import os

import mitsuba as mi
import numpy as np
import pytest

import mi_voldis  # noqa: F401
from mi_voldis.bench.geometry import BAND_NAMES, load_truth, main, true_depth
from mi_voldis.cameras import Camera, pixel_rays
from mi_voldis.data import load_dataset
from mi_voldis.metrics import dilate
from mi_voldis.synth.rigs import look_at

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_the_true_depth_is_the_distance_to_the_first_surface_along_each_ray_and_infinite_past_it():
    """A camera at z = -3 looking at a square of half-width 0.3 in the plane z = 0.5 and, behind its left
    half only, another at z = 0.8: each pixel's distance is (z_plane + 3) / d_z for the nearer plane its
    ray crosses inside the square, infinite where it crosses none."""
    def square(z, x0, half):
        return {"type": "rectangle", "to_world": mi.ScalarTransform4f().translate([x0, 0.0, z]).scale(half)}
    scene = mi.load_dict({"type": "scene", "near": square(0.5, 0.0, 0.3), "far": square(0.8, -0.3, 0.3)})
    camera = Camera(look_at([0.0, 0.0, -3.0], [0.0, 0.0, 0.0]), 30.0, 24, 18)
    t = true_depth(scene, camera)
    py, px = np.mgrid[0:camera.height, 0:camera.width]
    o, d = pixel_rays(camera, px.ravel() + 0.5, py.ravel() + 0.5)
    expected = np.full(len(o), np.inf)
    for z, x0, half in ((0.8, -0.3, 0.3), (0.5, 0.0, 0.3)):  # the nearer one last: it wins
        s = (z - o[:, 2]) / d[:, 2]
        at = o + s[:, None] * d
        inside = (np.abs(at[:, 0] - x0) < half) & (np.abs(at[:, 1]) < half)
        expected = np.where(inside, s, expected)
    expected = expected.reshape(t.shape)
    edge = np.isfinite(expected) != np.isfinite(t)  # pixel centres within float rounding of a square's edge
    assert edge.sum() <= 2
    both = np.isfinite(expected) & np.isfinite(t)
    assert both.sum() > 40 and (~np.isfinite(t)).sum() > 40
    assert np.abs(t[both] - expected[both]).max() < 1e-4


def test_the_truth_without_the_object_lies_behind_it_where_the_mask_shows_it_and_is_the_same_elsewhere(tiny_dataset):
    """The tabletop without its object's shapes (``--layer bg``): on a held-out view every pixel's true
    distance is the same as with the object, or farther; farther on the object's masked pixels (its
    mask: exact coverage), the same off them."""
    xml = os.path.join(ROOT, "scenes", "tabletop.xml")
    ds = load_dataset(tiny_dataset)
    view = ds.test[0]
    full, bg = (true_depth(load_truth(xml, layer), ds.cameras[view]) for layer in ("full", "bg"))
    both = np.isfinite(full) & np.isfinite(bg)
    assert (bg[both] >= full[both] - 1e-4).all()
    mask = ds.masks[view]
    assert mask.sum() > 5
    inner = mask & np.isfinite(full)
    assert np.mean(bg[inner] > full[inner] + 1e-3) > 0.8
    off = ~dilate(mask, 1) & both
    assert np.abs(bg[off] - full[off]).max() < 1e-4


def table(text):
    """The rows of the command's table: {(view, pixels): [numbers]}."""
    rows = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("| ") and cells[0] != "view":
            rows[cells[0], cells[1]] = [float(c) for c in cells[2:]]
    return rows


def test_the_command_prints_each_held_out_views_weight_by_band_and_their_mean(tiny_run, capsys):
    """On the tiny tabletop run, against the XML its dataset was rendered from: a row per held-out view and
    one for all, over the whole view and around the object, each a share per band and the weight no sample
    holds, summing to 1; around the object is a part of the whole, so its rows differ."""
    main([tiny_run, "--scene", os.path.join(ROOT, "scenes", "tabletop.xml")])
    rows = table(capsys.readouterr().out)
    test = [str(v) for v in mi_voldis.load_run(tiny_run).dataset.test]
    assert list(rows) == [(v, r) for v in test for r in ("whole", "around the object")] + [
        ("all", "whole"), ("all", "around the object")]
    assert rows["all", "whole"] != rows["all", "around the object"]
    for name, values in rows.items():
        assert len(values) == len(BAND_NAMES) + 1
        assert all(-1e-3 <= x <= 1.0 + 1e-3 for x in values), (name, values)
        assert abs(sum(values) - 1.0) < 5e-3, (name, values)


def test_the_background_layer_is_measured_in_the_hole_against_the_scene_without_the_object(tiny_run, capsys):
    """``--layer bg``: the same table for the background layer, its second region the hole."""
    main([tiny_run, "--scene", os.path.join(ROOT, "scenes", "tabletop.xml"), "--layer", "bg"])
    out = capsys.readouterr().out
    assert "object-free" in out
    rows = table(out)
    assert ("all", "the hole") in rows and ("all", "whole") in rows
    assert abs(sum(rows["all", "the hole"]) - 1.0) < 5e-3


@pytest.mark.parametrize("case", ["no run", "no scene", "bad views", "bad layer", "scene not a file"])
def test_the_command_refuses_what_it_cannot_score_in_one_line(case, tiny_run, tmp_path):
    """A folder that is no run, a dataset without its scene (the tabletop's carries none), a view set or a
    layer it does not know and a --scene that is not a file: each stops with one line naming what is wrong."""
    args = {"no run": [str(tmp_path)], "no scene": [tiny_run], "bad views": [tiny_run, "--views", "some"],
            "bad layer": [tiny_run, "--layer", "fg"],
            "scene not a file": [tiny_run, "--scene", str(tmp_path / "missing.xml")]}[case]
    with pytest.raises(SystemExit) as stop:
        main(args)
    message = str(stop.value)
    assert message.startswith("error: ") and "\n" not in message, message
    named = {"no run": os.path.join(str(tmp_path), "config.json"), "no scene": "scene/scene.xml",
             "bad views": "--views some", "bad layer": "--layer fg", "scene not a file": "missing.xml"}[case]
    assert named in message, message
