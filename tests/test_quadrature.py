"""Analytic cases of the volume-rendering quadrature."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import UNIT_BOX, axis_rays, box_transform, constant_field, integrator, numpy_layers, ortho_scene

from mi_voldis.field.activations import one_minus_exp, sigmoid, softplus
from mi_voldis.render.rays import render_rays

COLOR = np.array([0.8, 0.3, 0.1])
EMPTY = constant_field(1e-12, [0.5, 0.5, 0.5], UNIT_BOX)


@pytest.mark.parametrize("sigma", [1e-8, 1e-6, 1e-3, 0.1, 1.0, 10.0, 1e3, 1e6, 1e8])
@pytest.mark.parametrize("samples", [1, 7, 64, 256])
def test_homogeneous_box(sigma, samples):
    """A box of density sigma and colour c, crossed over length L = 2, gives c (1 - exp(-sigma L))."""
    integ = integrator(constant_field(sigma, COLOR, UNIT_BOX), EMPTY, samples=samples)
    o, d, u = axis_rays(32)
    out = numpy_layers(render_rays(integ, o, d, u, layers=("full",)))
    expected = COLOR * -np.expm1(-sigma * 2.0)
    assert np.abs(out["full"][0] - expected).max() < 1e-4
    assert np.abs(out["full"][0] / expected - 1).max() < 1e-3  # relative precision even at sigma = 1e-8
    # a ray that stops early sums its weights to 1 (its last sample takes the light left), in float32
    assert np.all((out["full"][1] >= 0) & (out["full"][1] <= 1 + 1e-6))


def test_homogeneous_box_through_mitsuba():
    """Same analytic answer through mi.render and an orthographic camera."""
    sigma = 0.7
    scene = ortho_scene({"type": "voldis", "samples": 32, "full": constant_field(sigma, COLOR, UNIT_BOX),
                         "bg": EMPTY, "mode": "full"}, extent=0.9)
    img = np.array(mi.render(scene))
    expected = COLOR * -np.expm1(-sigma * 2.0)
    assert np.abs(img[..., :3] - expected).max() < 1e-4
    names = scene.integrator().aov_names()
    assert np.abs(img[..., 3 + names.index("A")] + np.expm1(-sigma * 2.0)).max() < 1e-4


@pytest.mark.parametrize("samples", [64, 256])
def test_depth_of_thin_dense_slab(samples):
    """An opaque slab at z = 0.5, 0.04 thick (more than one sample spacing, so no ray skips it), is seen
    at distance 3.5 from z0 = -3, to within one sample spacing."""
    slab = constant_field(1e5, COLOR, box_transform([-1, -1, 0.5], [1, 1, 0.54]))
    room = constant_field(1e-9, COLOR, UNIT_BOX)  # widens the sampled interval to the unit box
    integ = mi.load_dict({"type": "voldis", "samples": samples, "full": slab, "bg": room})
    o, d, u = axis_rays(32)
    out = numpy_layers(render_rays(integ, o, d, u, layers=("full", "bg")))
    rgb, alpha, depth = out["full"]
    dt = 2.0 / samples
    assert np.abs(alpha - 1).max() < 1e-4
    assert np.all((depth >= 3.5) & (depth <= 3.5 + dt))
    assert np.abs(rgb - COLOR).max() < 1e-4


def test_activations_precision():
    x = mi.Float([1e-9, 1e-6, 1e-3, 0.5, 30.0, 1e6])
    np.testing.assert_allclose(np.array(one_minus_exp(x)), -np.expm1(-np.array(x, np.float64)), rtol=1e-6)
    r = mi.Float([-30.0, -18.42, -13.8, 0.0, 5.0, 100.0, 1e8])
    np.testing.assert_allclose(np.array(softplus(r)), np.logaddexp(0, np.array(r, np.float64)), rtol=1e-6)
    np.testing.assert_allclose(np.array(sigmoid(r)), 1 / (1 + np.exp(-np.array(r, np.float64))), rtol=1e-6)
    assert dr.all(dr.isfinite(softplus(mi.Float(-1e30, 1e30))))


@pytest.mark.parametrize("step", [0.05, 0.3, 5.0])
def test_step_size_sampling_is_exact_and_adapts(step):
    """With step_size, each ray takes ceil(length / step) samples (capped by samples): still exact for a
    homogeneous box, and a ray crossing a corner takes fewer samples than one crossing the middle."""
    sigma = 1.3
    integ = integrator(constant_field(sigma, COLOR, UNIT_BOX), EMPTY, samples=64, step_size=step)
    o, d, u = axis_rays(16)
    out = render_rays(integ, o, d, u, layers=("full",))
    np.testing.assert_allclose(np.array(out["full"][0]).T, np.broadcast_to(COLOR * -np.expm1(-2 * sigma), (16, 3)),
                               atol=1e-4)
    assert np.all(np.array(out["evaluated"]) == min(64, int(np.ceil(2.0 / step))))
    # a ray clipping the box's corner (0.28 long inside it) against one crossing it (2 long)
    short = render_rays(integ, mi.Point3f(0.4, 0.9, -1.4), dr.normalize(mi.Vector3f(1.0, 0.0, 1.0)), mi.Float(0.5),
                        ("full",))
    n_short = np.array(short["evaluated"])[0]
    assert n_short == min(64, int(np.ceil(0.2 * np.sqrt(2) / step)))


@pytest.mark.parametrize("stop", [0.3, 1e-2, 1e-3, 1e-4])
def test_rays_stop_where_transmittance_falls_below_stop_transmittance(stop):
    """Through a box of density sigma sampled every delta, a ray evaluates samples until its optical
    depth n sigma delta reaches -ln(stop): n = ceil(-ln(stop) / (sigma delta)); its last sample takes
    the light left, so its alpha is 1 (the whole box's, 1 - exp(-2 sigma), to within ``stop``) and its
    colour the box's, where without it both would be short by exp(-n sigma delta), up to ``stop``."""
    sigma, samples = 10.0, 256
    x = sigma * 2.0 / samples
    integ = integrator(constant_field(sigma, COLOR, UNIT_BOX), EMPTY, samples=samples, stop_transmittance=stop)
    o, d, u = axis_rays(16)
    out = render_rays(integ, o, d, u, layers=("full",))
    n = int(np.ceil(-np.log(stop) / x))
    assert np.all(np.array(out["evaluated"]) == n)
    rgb, alpha = np.array(out["full"][0]), np.array(out["full"][1])
    np.testing.assert_allclose(alpha, 1.0, rtol=1e-6)
    np.testing.assert_allclose(rgb, np.array(COLOR)[:, None] * np.ones((1, 16)), rtol=1e-5)
    assert np.all(np.abs(alpha + np.expm1(-2 * sigma)) <= stop)


def test_a_stop_for_a_block_renders_as_an_integrator_built_with_it_and_is_given_back_after():
    """``stopped_at`` (the fit's PSNR log at the fitted scene's stop): the same colours, alphas and samples
    as an integrator made with that stop, bit for bit; the integrator's own stop before and after."""
    box = constant_field(10.0, COLOR, UNIT_BOX)
    own, other = (integrator(box, EMPTY, samples=256, stop_transmittance=s) for s in (1e-4, 0.3))
    o, d, u = axis_rays(16)

    def run(integ):
        out = render_rays(integ, o, d, u, layers=("full",))
        return [np.array(x) for x in out["full"][:2]] + [np.array(out["evaluated"])]
    before = run(own)
    with own.stopped_at(0.3) as stopped:
        inside = run(stopped)
    after = run(own)
    for a, b in zip(inside, run(other)):
        np.testing.assert_array_equal(a, b)
    assert inside[2].max() < before[2].min()  # fewer samples: the stop did change
    for a, b in zip(after, before):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="stop_transmittance must be in \\(0, 1\\)"):
        with own.stopped_at(0.0):
            pass
    assert own.stop_transmittance == 1e-4


@pytest.mark.parametrize("value", [0.0, 1.0, -1e-3, 2.0])
def test_stop_transmittance_outside_0_1_is_refused(value):
    with pytest.raises(Exception, match="stop_transmittance must be in \\(0, 1\\)"):
        integrator(constant_field(1.0, COLOR, UNIT_BOX), EMPTY, stop_transmittance=value)
