"""The PyTorch benchmark reference renders and differentiates like the Dr.Jit march."""
import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="needs PyTorch: pip install .[clip] or .[bench]")

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
from helpers import box_transform, field_dict  # noqa: E402

from mi_voldis.bench.torch_reference import TorchGridField, measure, render  # noqa: E402
from mi_voldis.render.rays import render_rays  # noqa: E402

LO, HI = np.array([-1.0, -0.5, -0.8]), np.array([1.0, 0.7, 0.9])
SHAPE = (6, 5, 7)  # (Z, Y, X): distinct sizes catch swapped axes
SCALE = 2.0
SAMPLES = 32


@pytest.fixture(scope="module", params=[(0.0, 1e-4), (3.0, 5e-3)], ids=["faint", "opaque"])
def fields(request):
    """The same raw grids as a Dr.Jit ``voldis`` integrator (``full`` layer) and a TorchGridField, and
    the gradient tolerance (relative to the largest entry). The raw density has mean 0 (no ray reaches
    Dr.Jit's termination threshold: agreement to rounding) or 3 (many rays stop early in Dr.Jit,
    which drops the gradients behind the stopping point)."""
    offset, grad_atol = request.param
    rng = np.random.default_rng(7)
    density, color = rng.normal(offset, 1, SHAPE + (1,)), rng.normal(0, 1, SHAPE + (3,))
    box = box_transform(LO, HI)
    bg = field_dict(rng.normal(0, 0.5, (3, 3, 3, 1)), rng.normal(0, 0.5, (3, 3, 3, 3)), box, SCALE)
    integ = mi.load_dict({"type": "voldis", "full": field_dict(density, color, box, SCALE), "bg": bg,
                          "samples": SAMPLES}, optimize=False)
    return integ, TorchGridField.from_numpy(density, color, LO, HI, SCALE), grad_atol


def rays(seed=0):
    """Rays from outside aimed into the box, rays starting inside it, and rays that miss it (one of
    them parallel to an axis)."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(160, 3))
    outside = 3.0 * v / np.linalg.norm(v, axis=1, keepdims=True)
    inside = rng.uniform(LO, HI, (48, 3))
    o = np.concatenate([outside, inside, [[3.0, 0.0, 0.0], [0.0, 2.0, 0.0]]])
    d = np.concatenate([rng.uniform(0.8 * LO, 0.8 * HI, (160, 3)) - outside, rng.normal(size=(48, 3)),
                        [[0.0, 1.0, 0.0], [0.3, 1.0, 0.2]]])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    u = rng.uniform(0, 1, len(o))
    return [a.astype(np.float32) for a in (o, d, u)]


def drjit_render(integ, o, d, u):
    out = render_rays(integ, mi.Point3f(*o.T), mi.Vector3f(*d.T), mi.Float(u), layers=("full",))
    return out["full"][0], out["full"][1]


def torch_render(field, o, d, u):
    return render(field, torch.from_numpy(o), torch.from_numpy(d), torch.from_numpy(u), SAMPLES)


def test_matches_drjit_render(fields):
    integ, field, _ = fields
    o, d, u = rays()
    rgb, alpha = drjit_render(integ, o, d, u)
    rgb_t, alpha_t = torch_render(field, o, d, u)
    rgb, alpha = np.array(rgb).T, np.array(alpha)
    assert alpha.max() > 0.9 and np.all(alpha[:-2] > 0)
    np.testing.assert_array_equal(alpha[-2:], 0.0)
    np.testing.assert_allclose(rgb_t.numpy(), rgb, rtol=0, atol=2e-4)
    np.testing.assert_allclose(alpha_t.numpy(), alpha, rtol=0, atol=2e-4)


def test_matches_drjit_gradients(fields):
    integ, field, grad_atol = fields
    o, d, u = rays(1)
    rng = np.random.default_rng(2)
    w_rgb = rng.normal(0, 1, (len(o), 3)).astype(np.float32)
    w_alpha = rng.normal(0, 1, len(o)).astype(np.float32)

    params = mi.traverse(integ)
    keys = ("full.density", "full.color")
    for k in keys:
        dr.enable_grad(params[k])
    params.update()
    rgb, alpha = drjit_render(integ, o, d, u)
    w = mi.Color3f(*w_rgb.T)
    dr.backward(dr.sum(rgb[0] * w[0] + rgb[1] * w[1] + rgb[2] * w[2] + alpha * mi.Float(w_alpha)))
    expected = {k: np.array(dr.grad(params[k])) for k in keys}  # (Z, Y, X, C)
    for k in keys:
        dr.disable_grad(params[k])
    params.update()

    field.grid.requires_grad_(True)
    rgb_t, alpha_t = torch_render(field, o, d, u)
    (torch.sum(rgb_t * torch.from_numpy(w_rgb)) + torch.sum(alpha_t * torch.from_numpy(w_alpha))).backward()
    grad = field.grid.grad[0].numpy().transpose(1, 2, 3, 0)  # (Z, Y, X, 4)
    field.grid.requires_grad_(False)
    field.grid.grad = None

    for k, got in (("full.density", grad[..., :1]), ("full.color", grad[..., 1:])):
        want = expected[k]
        scale = np.abs(want).max()
        assert scale > 0, k
        np.testing.assert_allclose(got, want, rtol=0, atol=grad_atol * scale, err_msg=k)
        top = np.argsort(-np.abs(want).ravel())[:8]
        np.testing.assert_allclose(got.ravel()[top], want.ravel()[top], rtol=0.02, err_msg=k)


def test_measure_reports_throughput():
    result = measure(8, 8, 64, steps=1, warmup=1, threads=1)
    for phase in ("forward", "train"):
        assert np.isfinite(result[phase]["msps"]) and result[phase]["msps"] > 0
        assert np.isfinite(result[phase]["seconds"]) and result[phase]["seconds"] > 0


@pytest.mark.parametrize("keep", ["all", "some"])
def test_brick_reference_matches_drjit_bricks(keep):
    """TorchBrickField against the radiance_field plugin's brick grid, same bricks (every one, or a
    subset, so that lookups blend with the empty brick): renders and gradients of the packed data."""
    from mi_voldis.bench.torch_reference import TorchBrickField
    from mi_voldis.field.bricks import counts
    from mi_voldis.field.spec import brick_field_dict
    rng = np.random.default_rng(11)
    shape = (10, 9, 11)  # (Z, Y, X) vertices: 2 x 2 x 2 bricks of 8, partly filled
    density, color = rng.normal(0.5, 1, shape + (1,)), rng.normal(0, 1, shape + (3,))
    mask = None if keep == "all" else rng.uniform(size=counts(shape[::-1], 8)[::-1]) < 0.6
    box = box_transform(LO, HI)
    spec = brick_field_dict(density, color, box, SCALE, brick=8, keep=mask)
    integ = mi.load_dict({"type": "voldis", "full": spec, "bg": field_dict(np.full((2, 2, 2, 1), -20.0),
                          np.zeros((2, 2, 2, 3)), box), "samples": SAMPLES}, optimize=False)
    field = TorchBrickField.from_numpy(density, color, LO, HI, SCALE, brick=8, keep=mask)
    o, d, u = rays(3)
    params = mi.traverse(integ)
    dr.enable_grad(params["full.data"])
    params.update()
    rgb, alpha = drjit_render(integ, o, d, u)
    dr.backward(dr.sum(rgb[0] + 2 * rgb[1] - rgb[2] + alpha))
    expected = np.array(dr.grad(params["full.data"]))
    field.grid.requires_grad_(True)
    rgb_t, alpha_t = torch_render(field, o, d, u)
    np.testing.assert_allclose(rgb_t.detach().numpy(), np.array(rgb).T, atol=2e-4)
    np.testing.assert_allclose(alpha_t.detach().numpy(), np.array(alpha), atol=2e-4)
    (torch.sum(rgb_t * torch.tensor([1.0, 2.0, -1.0])) + torch.sum(alpha_t)).backward()
    got = field.grid.grad.numpy()
    want = expected.reshape(-1, 4)  # (slots x B^3 vertices, density + RGB), the empty brick first
    assert want.shape == got.shape and np.abs(want).max() > 0
    np.testing.assert_allclose(got, want, rtol=0, atol=5e-3 * np.abs(want).max())
