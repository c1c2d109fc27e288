"""Dense export to Mitsuba's gridvolume: exact on fields that trilinear interpolation reproduces, the
world-length conversion of scene densities, a scene file Mitsuba loads, and the script's errors."""
import os
import subprocess
import sys

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_voldis.field.dense_export import export_dense, sample_field, stretch, write_export
from mi_voldis.field.spec import box_transform, brick_field_dict, field_dict
from mi_voldis.io.vol import read_header, read_vol
from mi_voldis.scene import write_scene
from mi_voldis.space import SceneSpace

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LO, HI = np.array([-1.0, -0.5, 0.0]), np.array([1.0, 0.5, 2.0])


def linear_raw(shape, lo, hi):
    """Raw density 0.5 + x + 2 z and raw colour (x, y, -z) at the vertices of a grid over [lo, hi]
    (trilinear interpolation reproduces both exactly)."""
    z, y, x = np.meshgrid(*[np.linspace(lo[a], hi[a], n) for a, n in ((2, shape[0]), (1, shape[1]), (0, shape[2]))],
                          indexing="ij")
    return (0.5 + x + 2 * z)[..., None], np.stack([x, y, -z], -1)


def softplus(x):
    return np.logaddexp(0.0, x)


def sigmoid(x):
    return 1.0 / (1.0 + np.exp(-x))


@pytest.mark.parametrize("bricks", [False, True])
def test_export_of_a_world_field_matches_the_activated_field_at_cell_centres(bricks):
    density, color = linear_raw((9, 5, 17), LO, HI)
    make = brick_field_dict if bricks else field_dict
    field = mi.load_dict(make(density, color, box_transform(LO, HI), density_scale=3.0))
    lo, hi = LO + 0.1, HI - 0.2
    sigma, albedo = export_dense(field, SceneSpace(), lo, hi, (7, 4, 5), slab_vertices=40)
    axes = [lo[a] + (np.arange(n) + 0.5) * (hi[a] - lo[a]) / n for a, n in enumerate((7, 4, 5))]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    np.testing.assert_allclose(sigma[..., 0], 3.0 * softplus(0.5 + x + 2 * z), rtol=1e-5)
    np.testing.assert_allclose(albedo, sigmoid(np.stack([x, y, -z], -1)), atol=1e-6)
    outside = sample_field(field, SceneSpace(), np.array([[5.0, 0, 0], [0, 0, -0.01]]))[0]
    np.testing.assert_array_equal(outside, 0.0)


def test_scene_length_per_world_length():
    assert np.allclose(stretch(SceneSpace(), np.random.default_rng(0).normal(size=(10, 3))), 1.0)
    radius = 2.5
    m = np.diag([radius, radius, radius, 1.0])
    m[:3, 3] = [1.0, -2.0, 0.5]
    space = SceneSpace("contract", m, shell=1.0)
    inner = m[:3, 3] + np.random.default_rng(1).uniform(-0.9, 0.9, (20, 3)) * radius
    np.testing.assert_allclose(stretch(space, inner), 1.0 / radius, rtol=1e-5)
    # outside the inner cube, along an axis: contract(x) = 2 - 1/x for x = |x_n| > 1, so d/dx = 1/x^2 along
    # the axis and (2 - 1/x)/x across it; the stretch is their mean over the three axes (per world unit / R)
    xn = 4.0
    point = m[:3, 3] + np.array([xn * radius, 0.0, 0.0])
    expected = (1 / xn ** 2 + 2 * (2 - 1 / xn) / xn) / 3 / radius
    np.testing.assert_allclose(stretch(space, point[None]), expected, rtol=1e-4)


def test_contracted_export_is_density_per_world_unit():
    """A constant scene density s in contracted space is s / R per world unit inside the inner cube."""
    radius, raw = 2.0, 1.5
    m = np.diag([radius, radius, radius, 1.0])
    space = SceneSpace("contract", m, shell=1.0)
    box = box_transform([-2] * 3, [2] * 3)
    field = mi.load_dict(field_dict(np.full((3, 3, 3, 1), raw), np.zeros((3, 3, 3, 3)), box))
    sigma, albedo = export_dense(field, space, [-1.0] * 3, [1.0] * 3, (4, 4, 4))
    np.testing.assert_allclose(sigma, softplus(raw) / radius, rtol=1e-5)
    np.testing.assert_allclose(albedo, 0.5, atol=1e-6)


def test_written_scene_loads_in_mitsuba_and_its_gridvolume_returns_the_export(tmp_path):
    density, color = linear_raw((5, 5, 5), LO, HI)
    field = mi.load_dict(field_dict(density, color, box_transform(LO, HI)))
    sigma, albedo = export_dense(field, SceneSpace(), LO, HI, (8, 6, 10))
    path = write_export(str(tmp_path), "full", sigma, albedo, LO, HI)
    np.testing.assert_array_equal(read_vol(str(tmp_path / "full_sigma_t.vol")), np.clip(sigma, 0, None))
    np.testing.assert_allclose(read_header(str(tmp_path / "full_albedo.vol"))[4], LO, atol=1e-7)
    scene = mi.load_file(path)
    medium = scene.shapes()[0].interior_medium()
    assert medium is not None
    # the medium's extinction at cell centres is the exported sigma (gridvolume interpolates cell-centred values)
    rng = np.random.default_rng(0)
    idx = np.stack([rng.integers(0, n, 10) for n in (8, 6, 10)], -1)  # (x, y, z) cell indices
    centres = LO + (idx + 0.5) * (HI - LO) / np.array([8, 6, 10])
    mei = dr.zeros(mi.MediumInteraction3f, 10)
    mei.p = mi.Point3f(*centres.T.astype(np.float32))
    sigma_t = np.array(medium.get_scattering_coefficients(mei)[2])[0]
    np.testing.assert_allclose(sigma_t, sigma[idx[:, 2], idx[:, 1], idx[:, 0], 0], rtol=1e-4)
    # a radiance_field (``field``) is alive while Mitsuba's volpath traces its medium calls: it must not fail
    image = np.array(mi.render(scene, sensor=mi.load_dict({
        "type": "perspective", "fov": 40, "film": {"type": "hdrfilm", "width": 8, "height": 8},
        "to_world": mi.ScalarTransform4f().look_at([0, 0, -5], [0, 0, 1], [0, 1, 0])}), spp=4))
    assert np.all(np.isfinite(image)) and image.mean() > 0


def run_script(*args):
    return subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "export_vol.py"), *args],
                          capture_output=True, text=True, cwd=ROOT)


def test_export_script_writes_the_region_and_refuses_bad_input_in_one_line(tmp_path):
    density, color = linear_raw((5, 5, 5), LO, HI)
    fields = {"full": mi.load_dict(field_dict(density, color, box_transform(LO, HI))),
              "bg": mi.load_dict(field_dict(density - 1, color, box_transform(LO, HI)))}
    os.makedirs(tmp_path / "run")
    scene = write_scene(str(tmp_path / "run"), fields, {"samples": 16})
    done = run_script(scene, "--out", str(tmp_path / "vol"), "--field", "bg", "--resolution", "6")
    assert done.returncode == 0, done.stderr
    x, y, z, channels, lo, hi = read_header(str(tmp_path / "vol" / "bg_sigma_t.vol"))
    assert (x, y, z, channels) == (6, 3, 6) + (1,) and np.allclose(lo, LO) and np.allclose(hi, HI)
    for args, message in [(["--field", "moved"], "no field 'moved'"), (["--region", "0,0,0,1,1"], "--region expects 6"),
                          (["--region", "0,0,0,1,-1,1"], "--region needs x0 < x1")]:
        bad = run_script(scene, "--out", str(tmp_path / "bad"), *args)
        assert bad.returncode != 0 and message in bad.stderr and "Traceback" not in bad.stderr, bad.stderr
    missing = run_script(str(tmp_path / "nothing.xml"), "--out", str(tmp_path / "bad"))
    assert missing.returncode == 1 and "nothing.xml: no such scene file" in missing.stderr
