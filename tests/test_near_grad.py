"""Near-camera gradient scaling (``near_grad``, :mod:`mi_voldis.render.march`): with one sample per ray
at a known distance d the scaled gradient is the plain one times min(1, (d / r)^2), exactly; the values
are untouched; and the rig extent the fit's r is a fraction of."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import axis_rays, integrator, random_field

from mi_voldis.cameras import Camera, look_at
from mi_voldis.data.scene_box import rig_extent
from mi_voldis.render.rays import render_rays

ROLES = ("full", "bg")


def _gradients(integ, o, d, u, weights, near_grad):
    """Gradients of sum_r weights_r (R + alpha)_r over both layers, for every field's density and colour,
    and the layers' values."""
    params = mi.traverse(integ)
    keys = [f"{r}.{k}" for r in ROLES for k in ("density", "color")]
    for k in keys:
        dr.enable_grad(params[k])
    params.update()
    out = render_rays(integ, o, d, u, ROLES, near_grad=near_grad)
    loss = mi.Float(0.0)
    for layer in ROLES:
        rgb, alpha = out[layer][0], out[layer][1]
        loss += dr.sum(weights * (rgb[0] + alpha))
    dr.backward(loss)
    grads = {k: np.array(dr.grad(params[k])).ravel() for k in keys}
    values = {layer: np.array(out[layer][1]) for layer in ROLES}
    for k in keys:
        dr.disable_grad(params[k])
    params.update()
    return grads, values


@pytest.mark.parametrize("r", [6.0, 2.5])
def test_one_sample_per_ray_scales_by_distance_squared(r):
    """Rays along +z from z = -3 through the unit box take one sample each, at t = 2 + 2 u; the gradient
    with ``near_grad`` r equals the plain gradient of the loss with each ray weighted by
    min(1, (t / r)^2); r = 2.5 scales some rays and leaves the others (t >= 2.5) alone."""
    integ = integrator(random_field(11), random_field(12, scale=0.7), samples=1)
    o, d, u = axis_rays(24, seed=3)
    t = 2.0 + 2.0 * np.array(u)
    scale = np.minimum(1.0, (t / r) ** 2)
    ones = mi.Float(np.ones(24, np.float32))
    scaled, values = _gradients(integ, o, d, u, ones, r)
    plain, values_plain = _gradients(integ, o, d, u, mi.Float(scale.astype(np.float32)), 0.0)
    for k, g in plain.items():
        assert np.abs(g).max() > 0, k
        np.testing.assert_allclose(scaled[k], g, rtol=1e-4, atol=1e-6 * np.abs(g).max(), err_msg=k)
    for layer in ROLES:  # the primal does not change
        np.testing.assert_array_equal(values[layer], values_plain[layer])
    if r == 2.5:
        assert scale.min() < 0.9 and scale.max() == 1.0


def test_far_cameras_leave_gradients_alone():
    """Every sample farther than r: the gradient is the plain one, bit for bit, many samples a ray."""
    integ = integrator(random_field(5), random_field(6), samples=16)
    o, d, u = axis_rays(16, seed=8)
    ones = mi.Float(np.ones(16, np.float32))
    scaled, _ = _gradients(integ, o, d, u, ones, 1.9)  # samples lie at t in [2, 4]
    plain, _ = _gradients(integ, o, d, u, ones, 0.0)
    for k in plain:
        np.testing.assert_array_equal(scaled[k], plain[k])


def _camera(position, target):
    return Camera(look_at(np.asarray(position, float), np.asarray(target, float), np.array([0.0, 1.0, 0.0])),
                  50.0, 64, 48)


def test_rig_extent_is_the_orbit_radius_and_a_forward_rigs_spread():
    """An orbit at radius 2.5 (any height): 2.5; a 3 x 2 forward grid 0.2 / 0.1 apart: its corner's
    distance from the middle, whatever the depth it looks at."""
    centre = np.array([0.3, -0.2, 1.0])
    orbit = [_camera(centre + [2.5 * np.cos(a), 0.7, 2.5 * np.sin(a)], centre)
             for a in np.linspace(0, 2 * np.pi, 12, endpoint=False)]
    assert rig_extent(orbit) == pytest.approx(2.5, rel=1e-6)
    grid = [_camera([x, y, 0.0], [x, y, 40.0]) for x in (-0.2, 0.0, 0.2) for y in (-0.1, 0.1)]
    assert rig_extent(grid) == pytest.approx(np.hypot(0.2, 0.1), rel=1e-6)
