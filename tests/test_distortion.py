"""The distortion loss (Mip-NeRF 360) computed in one pass by the march: its value against the O(N^2)
definition on an analytic ray, and its gradient against finite differences."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import axis_rays, check_gradient, constant_field, integrator, random_field

from mi_voldis.field.spec import box_transform
from mi_voldis.render.rays import render_rays


def test_value_matches_the_double_sum():
    """A homogeneous box crossed along z by rays with jitter u: N samples at s_i = (i + u) delta,
    w_i = T_i alpha_i in closed form; L = sum_ij w_i w_j |s_i - s_j| + 1/3 sum_i w_i^2 delta."""
    sigma, n = 1.3, 24
    box = box_transform([-1, -1, -1], [1, 1, 1])
    integ = integrator(constant_field(sigma, [0.5, 0.5, 0.5], box), constant_field(1e-9, [0, 0, 0], box), samples=n)
    u = np.array([0.2, 0.5, 0.9])
    o = mi.Point3f(np.zeros(3), np.zeros(3), np.full(3, -3.0))
    out = render_rays(integ, o, dr.zeros(mi.Vector3f, 3) + mi.Vector3f(0, 0, 1), mi.Float(u), ("full",),
                      distortion=("full",))
    delta = 2.0 / n
    for r, ur in enumerate(u):
        s = (np.arange(n) + ur) * delta
        alpha = 1 - np.exp(-sigma * delta)
        w = (1 - alpha) ** np.arange(n) * alpha
        want = (w[:, None] * w[None] * np.abs(s[:, None] - s[None])).sum() + (w ** 2).sum() * delta / 3
        assert float(np.array(out["distortion"]["full"])[r]) == pytest.approx(want, rel=1e-4)


@pytest.mark.parametrize("layer", ["full", "bg"])
def test_gradient_matches_finite_differences(layer):
    integ = integrator(random_field(1), random_field(2, scale=0.7), samples=20)
    o, d, u = axis_rays(32, seed=4)
    weights = mi.Float(np.random.default_rng(5).uniform(0.5, 1.5, 32))

    def loss():
        out = render_rays(integ, o, d, u, layers=("full", "bg"), distortion=(layer,))
        return dr.sum(out["distortion"][layer] * weights) + dr.sum(out[layer][0][1]) * 0.1
    params = mi.traverse(integ)
    check_gradient(params, f"{layer}.density", loss)
    other = "bg" if layer == "full" else "full"
    dr.enable_grad(params[f"{other}.density"])
    params.update()
    dr.backward(loss())
    assert np.abs(np.array(dr.grad(params[f"{other}.density"]))).max() == 0.0


def test_object_rays_weigh_object_gain_times_as_much():
    """distortion_loss weights the rays inside the object mask by object_gain and no others: its density
    gradient on a half-masked batch is the unmasked half's plus object_gain times the masked half's, and
    it passes finite differences."""
    from mi_voldis.losses import distortion_loss
    integ = integrator(random_field(3), random_field(4), samples=20)
    o, d, u = axis_rays(32, seed=6)
    params = mi.traverse(integ)
    mask = mi.Float((np.arange(32) < 16).astype(np.float32))

    def grad(loss_of):
        dr.enable_grad(params["full.density"])
        params.update()
        dr.backward(loss_of(render_rays(integ, o, d, u, ("full",), distortion=("full",))["distortion"]["full"]))
        g = np.array(dr.grad(params["full.density"])).ravel()
        dr.disable_grad(params["full.density"])
        params.update()
        return g
    inside, outside = grad(lambda per_ray: dr.mean(mask * per_ray)), grad(lambda per_ray: dr.mean((1 - mask) * per_ray))
    weighted = grad(lambda per_ray: distortion_loss(per_ray, mask, 5.0))
    assert np.abs(inside).max() > 0 and np.abs(outside).max() > 0
    np.testing.assert_allclose(weighted, outside + 5.0 * inside, rtol=1e-4, atol=1e-6 * np.abs(weighted).max())
    check_gradient(params, "full.density", lambda: distortion_loss(
        render_rays(integ, o, d, u, ("full",), distortion=("full",))["distortion"]["full"], mask, 5.0))
