"""Layers a compositor can use: the "over" identity full = fg + (1 - fg.A) bg on rendered layers, RGB <= A
and finite values in every layer, linear light, and the EXR header read back (camera as Nuke reads it)."""
import os

import mitsuba as mi
import numpy as np
import pytest
from helpers import field_dict, ortho_scene, random_field

from mi_voldis.cameras import Camera, project
from mi_voldis.compositing import composite_channels, linear_layer
from mi_voldis.export import render_channels, render_scene_files
from mi_voldis.io.exr import read_exr, read_exr_header
from mi_voldis.synth.rigs import look_at

SHAPE = (8, 8, 8)


def background_and_object(seed=0):
    """A random background field and the full field: the same plus an opaque red block in one corner."""
    rng = np.random.default_rng(seed)
    density = rng.normal(-1.0, 1.0, SHAPE + (1,))
    color = rng.normal(0, 1, SHAPE + (3,))
    full_d, full_c = density.copy(), color.copy()
    full_d[1:4, 1:4, 1:4] = 6.0
    full_c[1:4, 1:4, 1:4] = [3.0, -3.0, -3.0]
    return field_dict(full_d, full_c), field_dict(density, color)


def test_foreground_over_background_rebuilds_the_scene(tmp_path):
    full, bg = background_and_object()
    spec = {"type": "voldis", "samples": 64, "full": full, "bg": bg}
    raw = render_channels(ortho_scene(spec, size=32, extent=1.0))
    out = composite_channels(raw)
    for name, value in out.items():
        assert np.all(np.isfinite(value)), name
    for layer in ("", "full.", "bg.", "fg."):
        a = out[f"{layer}A"]
        assert a.min() >= 0 and a.max() <= 1
        for c in "RGB":
            assert out[f"{layer}{c}"].min() >= 0 and np.all(out[f"{layer}{c}"] <= a + 1e-7), layer + c
    rgb = lambda p: np.stack([out[f"{p}{c}"] for c in "RGB"], -1)  # noqa: E731
    matte = out["fg.A"][..., None]
    rebuilt = rgb("fg.") + (1 - matte) * rgb("bg.")
    assert np.abs(rebuilt - rgb("full.")).max() <= 1e-3 + 1e-6  # at every pixel (IDENTITY_TOL)
    assert np.all(out["fg.A"] >= np.clip(raw["fg.coverage"], 0, 1) - 1e-6)  # at least the object's coverage
    # the object is in the matte, and the matte is empty where full and bg are the same field
    same = np.all(np.abs(np.stack([raw[f"full.{c}"] - raw[f"bg.{c}"] for c in "RGBA"], -1)) < 1e-6, axis=-1)
    assert same.any() and out["fg.A"][same].max() < 1e-3 and out["fg.A"].max() > 0.5
    assert out["fg.R"].sum() > 3 * out["fg.G"].sum()  # it is red
    assert np.all(out["fg_depth.Z"][out["fg.A"] == 0] == 0)


def exr_passes(names):
    """Channel names grouped as the readers group them. Nuke: layer = the name before the last dot
    (none: the main layer 'rgba'), channel = the token after it. Blender (multilayer): channel = the
    last token, pass = the token before it (a bare R/G/B/A: 'Combined', Z: 'Depth'), view layer = the
    tokens before that. Returns (Nuke's {layer: channels}, Blender's {(view layer, pass): channels})."""
    nuke, blender = {}, {}
    for name in names:
        layer, _, chan = name.rpartition(".")
        nuke.setdefault(layer or "rgba", set()).add(chan)
        tokens = name.split(".")
        if len(tokens) == 1:
            key = ("", "Depth" if name == "Z" else "Combined")
        else:
            key = (".".join(tokens[:-2]), tokens[-2])
        blender.setdefault(key, set()).add(tokens[-1])
    return nuke, blender


def test_exr_layers_read_as_blender_and_nuke_group_them(tmp_path):
    """Every colour layer of a written EXR is one RGBA pass and every depth its own Z pass, in Nuke's and
    Blender's grouping (a fifth channel in a colour pass leaves Blender's compositor without the image).
    Read back, fg over bg is full in RGB within 1e-3 at every pixel, and in alpha wherever a matte
    exists that gives both (a_min <= a_alpha + tol / (1 - bg.A), compositing's docstring); elsewhere
    over has (a_min - a_alpha)(1 - bg.A) more alpha. The background here is partly transparent, so
    alpha pins the matte."""
    from mi_voldis.compositing import IDENTITY_TOL, minimum_matte
    full, bg = background_and_object(2)
    scene = ortho_scene({"type": "voldis", "samples": 64, "full": full, "bg": bg}, size=32, extent=1.0)
    exr = render_scene_files(scene, str(tmp_path))[0]
    ch = read_exr(exr)
    nuke, blender = exr_passes(ch)
    rgba, z = {"R", "G", "B", "A"}, {"Z"}
    assert nuke == {"rgba": rgba, "full": rgba, "bg": rgba, "fg": rgba,
                    "depth": z, "full_depth": z, "bg_depth": z, "fg_depth": z}
    assert blender == {("", "Combined"): rgba, ("", "full"): rgba, ("", "bg"): rgba, ("", "fg"): rgba,
                       ("", "depth"): z, ("", "full_depth"): z, ("", "bg_depth"): z, ("", "fg_depth"): z}
    rgba_of = lambda p: np.stack([ch[f"{p}.{c}"] for c in "RGBA"], -1).astype(np.float64)  # noqa: E731
    fg, back, whole = rgba_of("fg"), rgba_of("bg"), rgba_of("full")
    assert back[..., 3].max() < 0.99 and fg[..., 3].max() > 0.5  # partly transparent background; an object
    over = fg + (1 - fg[..., 3:]) * back  # Porter-Duff over, premultiplied (oiiotool --over, Alpha Over)
    assert np.abs(over - whole)[..., :3].max() <= IDENTITY_TOL + 1e-6
    clear = 1 - back[..., 3]
    a_alpha = (whole[..., 3] - back[..., 3]) / clear
    a_min = minimum_matte(whole[..., :3], back[..., :3])
    both = a_min <= a_alpha + IDENTITY_TOL / clear + 1e-5
    assert both.mean() > 0.9 and np.abs(over - whole)[..., 3][both].max() <= IDENTITY_TOL + 1e-5
    np.testing.assert_allclose((over - whole)[..., 3][~both], ((a_min - a_alpha) * clear)[~both], atol=1e-4)


def test_layers_are_linear_light():
    rgb = np.array([[[0.5, 0.02, 1.0]]]) * 0.8
    lin, a = linear_layer(rgb, np.array([[0.8]]))
    c = rgb / 0.8
    want = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4) * 0.8
    np.testing.assert_allclose(lin, want, rtol=1e-6)
    lin, a = linear_layer(np.array([[[0.3, 0.3, 0.3]]]), np.array([[1e-6]]))  # tiny alpha: nothing explodes
    assert np.all(lin == 0) and a[0, 0] == pytest.approx(1e-6)


def test_exr_header_names_the_camera(tmp_path):
    full, bg = random_field(3), random_field(4)
    cam = Camera(look_at([0.4, 0.3, -3.0], [0, 0, 0]), 40.0, 16, 12, (0.05, -0.02))
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "voldis", "samples": 8, "full": full, "bg": bg}})
    exr = render_scene_files(scene, str(tmp_path), cameras=[("v", cam)])[0]
    header = read_exr_header(exr)
    assert header["chromaticities"] == pytest.approx((0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290))
    assert header["software"].startswith("mi-voldis") and "distance along the camera ray" in header["comments"]
    assert "command" in header
    points = np.array([[0.2, -0.1, 0.3], [-0.5, 0.4, -0.2]])
    u, v, _ = project(cam, points)
    hom = np.column_stack([points, np.ones(2)]) @ header["worldToNDC"].astype(np.float64)  # row vectors
    np.testing.assert_allclose(hom[:, 0] / hom[:, 3], u / cam.width, atol=1e-5)
    np.testing.assert_allclose(hom[:, 1] / hom[:, 3], v / cam.height, atol=1e-5)
    local = np.column_stack([points, np.ones(2)]) @ header["worldToCamera"].astype(np.float64)
    assert np.all(local[:, 2] > 0)  # +z is the viewing direction
    assert set(read_exr(exr)) >= {"R", "G", "B", "A", "depth.Z", "fg.A", "full_depth.Z"}
    for layer in ("composite", "full", "bg", "fg", "depth", "sheet"):
        assert os.path.isfile(tmp_path / f"v_{layer}.png")


def test_minimum_matte_is_the_smallest_valid_alpha():
    """For random premultiplied full / bg colours, a_min makes fg valid, and any smaller alpha does not."""
    from mi_voldis.compositing import minimum_matte
    rng = np.random.default_rng(1)
    full, bg = rng.uniform(0, 1, (500, 3)), rng.uniform(0, 1, (500, 3))
    a = minimum_matte(full, bg, tol=0.0)[:, None]
    fg = full - (1 - a) * bg
    assert np.all(fg >= -1e-12) and np.all(fg <= a + 1e-12)
    smaller = np.maximum(a - 1e-3, 0)
    fg = full - (1 - smaller) * bg
    bad = np.any((fg < -1e-12) | (fg > smaller + 1e-12), axis=-1)
    assert np.all(bad[a[:, 0] > 1e-3])
    assert np.all(minimum_matte(full, bg, tol=1e-3) <= a[:, 0])  # the slack only lowers it
