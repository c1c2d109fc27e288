"""Reverse-mode gradients (path replay) against central finite differences."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import UNIT_BOX, axis_rays, check_gradient, field_dict, integrator, ortho_scene, random_field

from mi_voldis.render.rays import render_rays


def weighted_loss(integ, layers, seed=0, samples=None):
    """Random linear functional of every output (RGB, alpha, depth) of the layers, on fixed rays."""
    o, d, u = axis_rays(64, seed=seed)
    rng = np.random.default_rng(seed + 100)
    w = {lay: [mi.Float(rng.normal(0, 1, 64)) for _ in range(5)] for lay in layers}

    def loss():
        out = render_rays(integ, o, d, u, layers=layers, samples=samples)
        total = mi.Float(0.0)
        for lay in layers:
            rgb, a, z = out[lay]
            total += dr.sum(rgb[0] * w[lay][0] + rgb[1] * w[lay][1] + rgb[2] * w[lay][2] + a * w[lay][3]
                            + (z * w[lay][4] * 0.1 if lay != "fg" else 0.0))
        return total
    return loss


@pytest.mark.parametrize("channels", [3, 6, 12])
@pytest.mark.parametrize("rule", ["paper", "c4", "density"])
def test_render_rays_gradients(channels, rule):
    integ = integrator(random_field(1, channels=channels), random_field(2, channels=channels, scale=0.5),
                       samples=24, composition=rule)
    params = mi.traverse(integ)
    loss = weighted_loss(integ, ("composite", "full", "bg", "fg"))
    for key in ("full.density", "full.color", "bg.density", "bg.color"):
        check_gradient(params, key, loss)


def test_fitting_layers_gradients_are_separate():
    """The full layer's loss reaches only the full field, the background layer's only the background."""
    integ = integrator(random_field(3), random_field(4), samples=16)
    params = mi.traverse(integ)
    o, d, u = axis_rays(32)
    for key in ("full.density", "bg.density"):
        dr.enable_grad(params[key])
    params.update()
    out = render_rays(integ, o, d, u, layers=("full",))
    dr.backward(dr.sum(out["full"][0][0]))
    assert dr.all(dr.grad(params["bg.density"]).array == 0)
    assert dr.any(dr.grad(params["full.density"]).array != 0)


def test_mitsuba_render_gradients():
    """mi.render + dr.backward (AOVs included) matches finite differences of the image it differentiates:
    the adjoint pass uses ``seed_grad``, so the finite differences render with that seed."""
    spec = {"type": "voldis", "samples": 16, "full": random_field(5), "bg": random_field(6, scale=0.5)}
    scene = ortho_scene(spec, size=6, extent=0.8)
    params = mi.traverse(scene)
    n_channels = 3 + len(scene.integrator().aov_names())
    weights = mi.TensorXf(np.random.default_rng(0).normal(0, 1, (6, 6, n_channels)).astype(np.float32))
    w = np.array(weights)
    for k, name in enumerate(scene.integrator().aov_names()):
        if name.endswith("Z"):  # depth = sum w t / sum w: smooth only where the layer is opaque enough
            w[..., 3 + k] *= 0.05 if name in ("full.Z", "bg.Z") else 0.0
        if name == "fg.coverage":  # the matte is an output for compositing, not differentiated
            w[..., 3 + k] = 0.0
    weights = mi.TensorXf(w)

    def loss():
        if dr.grad_enabled(params["integrator.full.density"]) or dr.grad_enabled(params["integrator.bg.color"]):
            img = mi.render(scene, params, seed=0, seed_grad=1)
        else:
            img = mi.render(scene, seed=1)
        return dr.sum(img * weights, axis=None)
    for key in ("integrator.full.density", "integrator.bg.color"):
        check_gradient(params, key, loss, rtol=0.03)


def test_gradients_with_an_early_stop():
    """Rays stopped at transmittance 0.05 (dense fields): the adjoint replays the primal's stop, so its
    gradients are those of the truncated sums (finite differences small enough not to move any ray's stop)."""
    rng = np.random.default_rng(7)
    full, bg = (field_dict(rng.normal(2.0, 1.0, (4, 4, 4)), rng.normal(0, 1, (4, 4, 4, 3)), UNIT_BOX) for _ in "ab")
    integ = integrator(full, bg, samples=24, stop_transmittance=0.05)  # every chain must fall below it
    o, d, u = axis_rays(64)
    ev = np.array(render_rays(integ, o, d, u, layers=("full", "bg"))["evaluated"])
    assert ev.min() < 24 and ev.max() > ev.min()  # rays stop early, at different samples
    params = mi.traverse(integ)
    loss = weighted_loss(integ, ("full", "bg"))
    for key in ("full.density", "full.color", "bg.density", "bg.color"):
        check_gradient(params, key, loss)
