"""Per-image colour corrections: the affine map, its penalty, and that a fit finds a photograph's
exposure change instead of baking it into the fields."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_voldis import exposure


def test_affine_map_and_penalty():
    rng = np.random.default_rng(0)
    params = rng.normal(0, 0.1, (2, exposure.WIDTH)).astype(np.float32)
    rgb = rng.uniform(0, 1, (5, 3)).astype(np.float32)
    view = np.array([0, 1, 1, 0, 1])
    out = np.array(exposure.apply(mi.Float(params.ravel()), mi.UInt32(view), mi.Color3f(*rgb.T))).T
    m = exposure.matrices(mi.Float(params.ravel()))
    want = np.einsum("nij,nj->ni", m[view, :, :3], rgb) + m[view, :, 3]
    np.testing.assert_allclose(out, want, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(exposure.matrices(exposure.identity(3))[:, :, :3], np.broadcast_to(np.eye(3), (3, 3, 3)))
    assert float(exposure.penalty(mi.Float(params.ravel()), 2.0)[0]) == pytest.approx(2 * (params ** 2).sum() / 2,
                                                                                       rel=1e-5)


def test_gradient_reaches_the_corrections():
    params = exposure.identity(2)
    dr.enable_grad(params)
    rgb = mi.Color3f(0.2, 0.5, 0.8)
    out = exposure.apply(params, mi.UInt32(1), rgb)
    dr.backward(dr.sum(out[0]))  # d/dE_1[0, :] = rgb, d/db_1[0] = 1; nothing for image 0
    g = np.array(dr.grad(params)).reshape(2, -1)
    np.testing.assert_allclose(g[1, :3], [0.2, 0.5, 0.8], rtol=1e-6)
    assert g[1, 9] == pytest.approx(1.0) and not g[0].any() and not g[1, 3:9].any()


def test_centring_leaves_per_image_deviations_only():
    rng = np.random.default_rng(1)
    params = rng.normal(0, 0.1, (4, exposure.WIDTH)).astype(np.float32)
    out = np.array(exposure.centre(mi.Float(params.ravel()))).reshape(4, -1)
    np.testing.assert_allclose(out.mean(axis=0), 0.0, atol=1e-7)
    np.testing.assert_allclose(out, params - params.mean(axis=0), atol=1e-6)
