"""The radiance_field plugin: interpolation, activations, spherical harmonics, traversal."""
import os

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import box_transform, field_dict

import mi_voldis
from mi_voldis.field.activations import sigmoid, softplus


def load(density, color, to_world=None):
    return mi.load_dict(field_dict(density, color, to_world))


def test_trilinear_reproduces_linear_functions():
    """Vertex-aligned trilinear interpolation is exact for an affine function of position."""
    shape = (5, 4, 3)  # (Z, Y, X)
    z, y, x = np.meshgrid(*[np.linspace(0, 1, n) for n in shape], indexing="ij")
    raw = (0.5 + 2 * x - 3 * y + 1.5 * z)[..., None]
    field = load(raw, np.zeros(shape + (3,)))
    rng = np.random.default_rng(0)
    p = rng.uniform(0, 1, (3, 200))
    sigma, _ = field.eval_local(mi.Point3f(p), mi.Vector3f(0, 0, 1))
    expected = np.logaddexp(0, 0.5 + 2 * p[0] - 3 * p[1] + 1.5 * p[2])
    np.testing.assert_allclose(np.array(sigma), expected, rtol=1e-5)


def test_outside_the_box_is_empty():
    field = load(np.full((2, 2, 2, 1), 3.0), np.zeros((2, 2, 2, 3)))
    sigma, _ = field.eval_local(mi.Point3f([-0.01, 0.5, 1.01], [0.5, 0.5, 0.5], [0.5, 0.5, 0.5]), mi.Vector3f(0, 0, 1))
    np.testing.assert_allclose(np.array(sigma), [0.0, np.logaddexp(0, 3.0), 0.0], rtol=1e-6)


def test_spherical_harmonics_view_dependence_and_promotion():
    rng = np.random.default_rng(1)
    c0 = rng.normal(0, 1, (2, 2, 2, 3))
    c1 = rng.normal(0, 1, (2, 2, 2, 9))
    deg0 = load(np.zeros((2, 2, 2, 1)), c0)
    promoted = load(np.zeros((2, 2, 2, 1)), np.concatenate([c0, np.zeros_like(c1)], axis=-1))
    view = load(np.zeros((2, 2, 2, 1)), np.concatenate([c0, c1], axis=-1))
    p = mi.Point3f(0.3, 0.6, 0.2)
    for d in ([0, 0, 1], [1, 0, 0], [0.6, -0.8, 0]):
        d = mi.Vector3f(d)
        np.testing.assert_allclose(np.array(promoted.eval_local(p, d)[1]), np.array(deg0.eval_local(p, d)[1]),
                                   atol=1e-6)
    a = np.array(view.eval_local(p, mi.Vector3f(0, 0, 1))[1])
    b = np.array(view.eval_local(p, mi.Vector3f(0, 0, -1))[1])
    assert np.abs(a - b).max() > 1e-3
    # degree 1 by hand: logit = C0 + sum_k Y_k(d) / Y_0 C_k at a vertex
    d = np.array([0.6, -0.8, 0.0])
    basis = np.array(dr.sh_eval(mi.Vector3f(d), 1)).ravel()
    logit = c0[0, 0, 0] + sum(basis[k] / basis[0] * c1[0, 0, 0, 3 * (k - 1):3 * k] for k in (1, 2, 3))
    got = np.array(view.eval_local(mi.Point3f(0, 0, 0), mi.Vector3f(d))[1]).ravel()
    np.testing.assert_allclose(got, 1 / (1 + np.exp(-logit)), rtol=1e-5)


def test_grey_view_dependence_is_rgb_harmonics_with_equal_channels():
    """6 colour channels: an RGB mean and one coefficient a degree-1 harmonic, which is the 12-channel field
    whose R, G and B coefficients of each harmonic are equal; its zero extension from degree 0 changes nothing."""
    rng = np.random.default_rng(2)
    c0, g = rng.normal(0, 1, (2, 2, 2, 3)), rng.normal(0, 1, (2, 2, 2, 3))
    grey = load(np.zeros((2, 2, 2, 1)), np.concatenate([c0, g], axis=-1))
    rgb = load(np.zeros((2, 2, 2, 1)), np.concatenate([c0, np.repeat(g, 3, axis=-1)], axis=-1))
    flat = load(np.zeros((2, 2, 2, 1)), np.concatenate([c0, np.zeros_like(g)], axis=-1))
    deg0 = load(np.zeros((2, 2, 2, 1)), c0)
    assert (grey.sh_degree, grey.grey, rgb.grey) == (1, True, False)
    p = mi.Point3f(rng.uniform(0, 1, (3, 50)))
    for d in ([0, 0, 1], [1, 0, 0], [0.6, -0.8, 0], [-0.36, 0.48, 0.8]):
        d = mi.Vector3f(d)
        np.testing.assert_allclose(np.array(grey.eval_local(p, d)[1]), np.array(rgb.eval_local(p, d)[1]), atol=1e-6)
        np.testing.assert_allclose(np.array(flat.eval_local(p, d)[1]), np.array(deg0.eval_local(p, d)[1]), atol=1e-6)
    a = np.array(grey.eval_local(p, mi.Vector3f(0, 0, 1))[1])
    b = np.array(grey.eval_local(p, mi.Vector3f(0, 0, -1))[1])
    assert np.abs(a - b).max() > 1e-2


def gated(density, color, to_world=None, gate=True):
    return mi.load_dict({**field_dict(density, color, to_world, density_scale=4.0), "sh_gate": gate})


@pytest.mark.parametrize("channels", [6, 12])
def test_gated_view_dependence_follows_a_voxels_opacity(channels):
    """``sh_gate``: logit = C0 + g sum_k Y_k(d) / Y_0 C_k with g = 1 - exp(-s softplus(D) h), h the voxel edge
    (here a 3 x 2 x 2 box over 3 x 3 x 3 vertices: h = 1.5): a faint density shows its mean colour from every
    side, an opaque one the ungated colour, and in between exactly the formula."""
    rng = np.random.default_rng(3)
    c = rng.normal(0, 1, (3, 3, 3, channels))
    box = box_transform([0, 0, 0], [3, 2, 2])
    p = mi.Point3f(0.25, 0.5, 0.75)
    dirs = [mi.Vector3f(0, 0, 1), mi.Vector3f(0, 0, -1), mi.Vector3f(0.6, -0.8, 0)]
    faint = gated(np.full((3, 3, 3, 1), -14.0), c, box)
    colours = [np.array(faint.eval_local(p, d)[1]).ravel() for d in dirs]
    mean = np.array(load(np.full((3, 3, 3, 1), -14.0), c[..., :3], box).eval_local(p, dirs[0])[1]).ravel()
    for got in colours:
        np.testing.assert_allclose(got, mean, atol=1e-5)
    opaque, plain = gated(np.full((3, 3, 3, 1), 9.0), c, box), gated(np.full((3, 3, 3, 1), 9.0), c, box, gate=False)
    for d in dirs:
        np.testing.assert_allclose(np.array(opaque.eval_local(p, d)[1]), np.array(plain.eval_local(p, d)[1]), atol=1e-6)
    raw = -0.7  # softplus 0.403, sigma h = 4 * 0.403 * 1.5: g = 0.911
    half = gated(np.full((3, 3, 3, 1), raw), c, box)
    g = 1 - np.exp(-4.0 * np.logaddexp(0, raw) * 1.5)
    d = np.array([0.6, -0.8, 0.0])
    basis = np.array(dr.sh_eval(mi.Vector3f(d), 1)).ravel()
    coeffs = c[0, 0, 0, 3:] if channels == 12 else np.repeat(c[0, 0, 0, 3:], 3)
    logit = c[0, 0, 0, :3] + g * sum(basis[k] / basis[0] * coeffs[3 * (k - 1):3 * k] for k in (1, 2, 3))
    got = np.array(half.eval_local(mi.Point3f(0, 0, 0), mi.Vector3f(d))[1]).ravel()
    np.testing.assert_allclose(got, 1 / (1 + np.exp(-logit)), rtol=1e-5)


def test_the_gate_passes_no_gradient_to_density_and_scales_the_coefficients():
    """d colour / d C_k is g times the ungated one (finite differences agree), and the colour's gradient
    reaches the density by no path: the gate is held constant in the derivative."""
    rng = np.random.default_rng(4)
    density, c = np.full((2, 2, 2, 1), -0.7), rng.normal(0, 1, (2, 2, 2, 6))
    p, d = mi.Point3f(0.3, 0.6, 0.2), mi.Vector3f(0.6, -0.8, 0)

    def colour_sum(gate, color):
        f = gated(density, color, gate=gate)
        params = mi.traverse(f)
        dr.enable_grad(params["density"], params["color"])
        params.update()
        total = dr.sum(f.eval_local(p, d)[1][0])
        dr.backward(total)
        return float(total[0]), np.array(dr.grad(params["density"])), np.array(dr.grad(params["color"]))

    value, g_density, g_color = colour_sum(True, c)
    _, g_density_plain, g_plain = colour_sum(False, c)
    assert np.abs(g_density).max() == 0.0 and np.abs(g_density_plain).max() == 0.0
    # per vertex, d R / d C_k over d R / d C_0 (red's mean) is g Y_k(d) / Y_0 (h = 1 here), and without the gate
    # Y_k(d) / Y_0
    gate = 1 - np.exp(-4.0 * np.logaddexp(0, -0.7) * 1.0)
    basis = np.array(dr.sh_eval(d, 1)).ravel()
    for grads, factor in ((g_color, gate), (g_plain, 1.0)):
        expected = np.broadcast_to(factor * basis[1:] / basis[0], grads[..., 3:].shape)
        np.testing.assert_allclose(grads[..., 3:] / grads[..., :1], expected, rtol=1e-4)
    eps = 1e-3
    bumped = c.copy()
    bumped[0, 0, 0, 4] += eps
    fd = (colour_sum(True, bumped)[0] - value) / eps
    assert abs(fd - g_color[0, 0, 0, 4]) < 2e-3 * max(1.0, abs(fd))
    with pytest.raises(RuntimeError, match="sh_gate must be a boolean"):  # Mitsuba wraps the plugin's error
        mi.load_dict({**field_dict(density, c), "sh_gate": "yes"})


def test_box_transform_places_the_grid():
    field = load(np.full((2, 2, 2, 1), 1.0), np.zeros((2, 2, 2, 3)), box_transform([1, 2, 3], [3, 6, 4]))
    local = field.world_to_local @ np.array([2.0, 4.0, 3.5, 1.0])
    np.testing.assert_allclose(local[:3], [0.5, 0.5, 0.5])


def test_traverse_update_repacks():
    field = load(np.zeros((2, 2, 2, 1)), np.zeros((2, 2, 2, 3)))
    params = mi.traverse(field)
    assert set(params.keys()) == {"density", "color"}
    params["density"] = mi.TensorXf(np.full((2, 2, 2, 1), 2.0, np.float32))
    params.update()
    sigma, color = field.eval_local(mi.Point3f(0.5, 0.5, 0.5), mi.Vector3f(0, 0, 1))
    np.testing.assert_allclose(np.array(sigma), [np.logaddexp(0, 2.0)], rtol=1e-6)
    np.testing.assert_allclose(np.array(color).ravel(), [0.5, 0.5, 0.5])
    params["color"] = mi.TensorXf(np.zeros((2, 2, 2, 5), np.float32))
    with pytest.raises(ValueError, match="3, 6, 12 or 27 channels"):
        params.update()


def test_activation_helpers_match_numpy():
    x = np.linspace(-30, 30, 61)
    np.testing.assert_allclose(np.array(sigmoid(mi.Float(x))), 1 / (1 + np.exp(-x)), rtol=1e-6)
    np.testing.assert_allclose(np.array(softplus(mi.Float(x))), np.logaddexp(0, x), rtol=1e-6)


def test_variant_checks():
    with pytest.raises(ValueError, match="differentiable RGB variant"):
        mi_voldis.check_variant("scalar_rgb")
    with pytest.raises(ValueError, match="differentiable RGB variant"):
        mi_voldis.check_variant("llvm_ad_spectral")
    mi_voldis.set_variant(mi.variant())  # re-registration keeps the plugins loadable
    assert load(np.zeros((2, 2, 2, 1)), np.zeros((2, 2, 2, 3))).shape == (2, 2, 2)


no_cuda = pytest.mark.skipif(dr.has_backend(dr.JitBackend.CUDA), reason="this machine has a CUDA device")


@no_cuda
def test_cuda_variant_without_a_device_is_one_clear_error():
    with pytest.raises(ValueError, match="'cuda_ad_rgb'.*no CUDA device or driver found"):
        mi_voldis.set_variant("cuda_ad_rgb")
    assert mi.variant() != "cuda_ad_rgb"


@no_cuda
@pytest.mark.parametrize("script", [["bench.py", "--step-profile"], ["train.py", "data", "--out", "run"],
                                    ["demo.py"]])
def test_scripts_with_cuda_variant_and_no_device_say_so_in_one_line(script, tmp_path):
    import subprocess
    import sys
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    done = subprocess.run([sys.executable, os.path.join(root, "scripts", script[0]), *script[1:], "--variant",
                           "cuda_ad_rgb"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 1
    assert done.stderr.splitlines() == ["error: variant 'cuda_ad_rgb' (--variant or $MI_VOLDIS_VARIANT): no CUDA "
                                        "device or driver found on this machine; use llvm_ad_rgb"]
    assert not os.listdir(tmp_path)


def test_pack_interleaves_channels_and_its_adjoint_gathers_them_back():
    from mi_voldis.field import grid
    rng = np.random.default_rng(3)
    d = rng.normal(size=(2, 3, 4, 1)).astype(np.float32)
    c = rng.normal(size=(2, 3, 4, 12)).astype(np.float32)  # 13 channels: packet width 16, 3 padding
    td, tc = mi.TensorXf(d), mi.TensorXf(c)
    dr.enable_grad(td, tc)
    packed = grid.pack([td, tc])
    expected = np.concatenate([d, c, np.zeros((2, 3, 4, 3), np.float32)], axis=3).ravel()
    assert np.array_equal(np.array(packed), expected)
    weights = rng.normal(size=expected.size).astype(np.float32)
    dr.backward(dr.sum(packed * mi.Float(weights)))
    w = weights.reshape(2, 3, 4, 16)
    assert np.array_equal(np.array(dr.grad(td)), w[..., :1])
    assert np.array_equal(np.array(dr.grad(tc)), w[..., 1:13])


def test_the_field_package_imports_no_layer_above_it():
    """``mi_voldis.field`` (what a field is) stands under the plugins, the renderer, fitting and the tasks,
    which all import it: none of its modules may import them back."""
    import ast
    import pathlib

    import mi_voldis.field
    above = {"plugins", "render", "fit", "tasks", "bench", "optim", "api", "scene"}
    found = []
    for path in pathlib.Path(mi_voldis.field.__file__).parent.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level >= 2:
                target = (node.module or "").split(".")[0]
                names = [target] if target else [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("mi_voldis."):
                names = [node.module.split(".")[1]]
            elif isinstance(node, ast.Import):
                names = [a.name.split(".")[1] for a in node.names if a.name.startswith("mi_voldis.")]
            else:
                continue
            found += [f"{path.name}: {n}" for n in names if n in above]
    assert not found, found
