"""Hard numerical cases: every output and gradient finite, alphas in [0, 1]."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import UNIT_BOX, field_dict, integrator, numpy_layers, random_field

from mi_voldis.render.rays import render_rays

ALL = ("composite", "full", "bg", "fg")


def hard_rays():
    """Rays that miss, graze faces and edges, start inside, touch a corner, and ordinary ones."""
    o = [(0, 0, -3), (5, 5, -3), (1, 0, -3), (1, 1, -3), (-1, -1, -3), (0, 0, 0), (0.3, -0.2, 0.9),
         (-3, 1, 1), (-3, -1, 0), (1, 1, -1), (0.2, 0.1, -3)]
    d = [(0, 0, 1), (0, 0, 1), (0, 0, 1), (0, 0, 1), (0, 0, 1), (0, 0, 1), (0, 0, -1),
         (1, 0, 0), (1, 0, 0), (-1, -1, -1), (0, 0, 1)]
    d = np.array(d, np.float64)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = np.array(o, np.float64)
    return mi.Point3f(*o.T), mi.Vector3f(*d.T), mi.Float(np.linspace(0.05, 0.95, len(o)))


def run_and_check(integ, keys=("full.density", "full.color", "bg.density", "bg.color"), rules=None):
    params = mi.traverse(integ)
    for key in keys:
        dr.enable_grad(params[key])
    params.update()
    o, d, u = hard_rays()
    out = render_rays(integ, o, d, u, layers=ALL)
    loss = mi.Float(0.0)
    for layer in ALL:
        rgb, a, z = out[layer]
        loss += dr.sum(rgb[0] + rgb[1] + rgb[2] + a + z)
    dr.backward(loss)
    res = numpy_layers(out)
    for layer, (rgb, a, z) in res.items():
        assert np.all(np.isfinite(rgb)) and np.all(np.isfinite(a)) and np.all(np.isfinite(z)), layer
    for layer in ("full", "bg"):
        assert np.all((res[layer][1] >= 0) & (res[layer][1] <= 1)), layer
    for key in keys:
        assert dr.all(dr.isfinite(dr.grad(params[key]).array)), key
    return res


@pytest.mark.parametrize("rule", ["paper", "c4", "density"])
@pytest.mark.parametrize("raw_density", [1e8, 1e4, 0.0, -100.0])
def test_extreme_densities(rule, raw_density):
    rng = np.random.default_rng(0)
    dense = field_dict(np.full((3, 3, 3, 1), raw_density) + rng.normal(0, 1, (3, 3, 3, 1)),
                       rng.normal(0, 1, (3, 3, 3, 3)), UNIT_BOX)
    res = run_and_check(integrator(dense, random_field(1), samples=16, composition=rule))
    if raw_density == 1e8:
        assert np.abs(res["full"][1][[0, 5, 10]] - 1.0).max() < 1e-6  # opaque wherever the ray enters


def test_all_zero_fields():
    zero = field_dict(np.zeros((2, 2, 2, 1)), np.zeros((2, 2, 2, 3)), UNIT_BOX)
    zero_bg = field_dict(np.zeros((3, 3, 3, 1)), np.zeros((3, 3, 3, 3)), UNIT_BOX)  # not merged with `zero`
    res = run_and_check(integrator(zero, zero_bg, samples=8))
    assert np.all(res["fg"][1] == 0)


def test_missing_rays_are_empty():
    res = run_and_check(integrator(random_field(2), random_field(3), samples=8))
    for layer in ALL:  # ray 1 misses, ray 9 points away from the box
        assert np.all(res[layer][0][[1, 9]] == 0) and np.all(res[layer][1][[1, 9]] == 0)


def test_zero_length_interval():
    """t_min == t_max: nothing is sampled, and nothing is NaN."""
    integ = integrator(random_field(4), random_field(5), samples=8)
    o, d, u = hard_rays()
    out = numpy_layers(render_rays(integ, o, d, u, layers=ALL, t_min=2.0, t_max=2.0))
    for rgb, a, z in out.values():
        assert np.all(rgb == 0) and np.all(a == 0) and np.all(z == 0)


def test_grazing_and_inside_rays_see_the_field():
    """A ray along a face (x = 1) and one starting at the centre both integrate the field."""
    res = run_and_check(integrator(random_field(6), random_field(7), samples=16))
    assert res["full"][1][2] > 0 and res["full"][1][5] > 0
