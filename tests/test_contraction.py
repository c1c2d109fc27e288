"""Contracted space: the contraction and its inverse, step lengths, analytic renders, gradients (with and
without the replay record), and empty-space skipping that never steps over a thin dense feature."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import check_gradient, constant_field, random_field

from mi_voldis.field.spec import box_transform, field_dict
from mi_voldis.render import march
from mi_voldis.render.rays import render_rays
from mi_voldis.space import SceneSpace
from mi_voldis.transforms import to_scalar_transform

M = np.diag([0.5, 0.5, 0.5, 1.0])  # inner cube: half-size 0.5 world units around the origin
CUBE = box_transform([-2, -2, -2], [2, 2, 2])


def contracted(full, bg, step=0.01, samples=4096, **props):
    return mi.load_dict({"type": "voldis", "samples": samples, "step_size": step, "contract_to_world":
                         to_scalar_transform(M), "contract_shell": 1.0, "full": full, "bg": bg, **props})


@pytest.mark.parametrize("shell", [1.0, 0.25])
def test_contraction_round_trips_and_its_step_length_is_its_derivative(shell):
    space = SceneSpace("contract", M, shell=shell)
    rng = np.random.default_rng(0)
    world = rng.normal(0, 5, (500, 3))
    scene = space.from_world_np(world)
    assert np.abs(scene).max() < 1 + shell
    np.testing.assert_allclose(space.to_world_np(scene), world, atol=1e-9)
    np.testing.assert_allclose(np.array(space.from_world(mi.Point3f(*world.T))).T, scene, atol=1e-5)
    x = mi.Point3f(*rng.normal(0, 3, (3, 300)))
    d = rng.normal(0, 1, (3, 300))
    d = mi.Vector3f(*(d / np.linalg.norm(d, axis=0)))
    eps = 1e-3
    fd = (np.array(space.contract(x + eps * d)) - np.array(space.contract(x - eps * d))) / (2 * eps)
    np.testing.assert_allclose(np.array(space.step_length(x, d)), np.linalg.norm(fd, axis=0), atol=5e-4)


def test_scene_depth_is_the_contracted_chord_and_its_gradient_matches_finite_differences():
    """From the centre along +x with M's half-size 0.5: the depth is 2t inside the cube, 2 - 1/(2t)
    beyond it (shell 1), tending to 2 at infinity; in world space it is t itself."""
    space = SceneSpace("contract", M, shell=1.0)
    o, d = mi.Point3f(0, 0, 0), mi.Vector3f(1, 0, 0)
    t = mi.Float([0.1, 0.4, 2.0, 50.0])
    dr.enable_grad(t)
    depth = space.scene_depth(o, d, t)
    dr.backward(dr.sum(depth))
    np.testing.assert_allclose(np.array(depth), [0.2, 0.8, 1.75, 1.99], rtol=1e-5)
    np.testing.assert_allclose(np.array(dr.grad(t)), [2.0, 2.0, 0.125, 0.0002], rtol=1e-3)
    # off the axes, from a point off the centre: the gradient against central differences
    rng = np.random.default_rng(1)
    o = mi.Point3f(*rng.normal(0, 0.3, (3, 50)))
    dn = rng.normal(0, 1, (3, 50))
    d = mi.Vector3f(*(dn / np.linalg.norm(dn, axis=0)))
    t = mi.Float(rng.uniform(0.05, 20.0, 50))
    dr.enable_grad(t)
    dr.backward(dr.sum(space.scene_depth(o, d, t)))
    eps = 1e-3
    fd = (np.array(space.scene_depth(o, d, t + eps)) - np.array(space.scene_depth(o, d, t - eps))) / (2 * eps)
    np.testing.assert_allclose(np.array(dr.grad(t)), fd, rtol=2e-2, atol=1e-4)
    world = SceneSpace("world")
    np.testing.assert_array_equal(np.array(world.scene_depth(o, d, mi.Float(3.0))), 3.0)


def test_homogeneous_slab_in_the_shell_is_analytic():
    """Density sigma per scene unit over the scene-space box z in [1.5, 5/3] (world z in [1, 1.5]): a ray
    along z sees alpha = 1 - exp(-sigma L), L = 1/6 its scene length, to within a step."""
    lo, hi = [-0.3, -0.3, 1.5], [0.3, 0.3, 2 - 1 / 3]
    integ = contracted(constant_field(3.0, [0.2, 0.5, 0.9], box_transform(lo, hi)),
                       constant_field(1e-9, [0, 0, 0], box_transform(lo, hi)), step=0.001)
    u = mi.Float(np.random.default_rng(1).uniform(0, 1, 64))
    out = render_rays(integ, mi.Point3f(0.0, 0.0, 0.0), mi.Vector3f(0, 0, 1), u, ("full",))
    np.testing.assert_allclose(np.array(out["full"][1]), 1 - np.exp(-3.0 / 6), atol=3e-3)
    z = np.array(out["full"][2])  # depth in world units: inside the slab's world extent
    assert (z > 1.0).all() and (z < 1.5).all()


@pytest.mark.parametrize("record", [True, False])
def test_gradients_match_finite_differences(monkeypatch, record):
    if not record:
        monkeypatch.setattr(march, "RECORD_BYTES", 0)
    integ = contracted(random_field(1, shape=(6, 6, 6), to_world=CUBE), random_field(2, shape=(6, 6, 6), to_world=CUBE),
                       step=0.05, samples=256)
    rng = np.random.default_rng(0)
    n = 32
    o = mi.Point3f(*rng.uniform(-0.2, 0.2, (3, n)))
    d = rng.normal(size=(3, n))
    d = mi.Vector3f(*(d / np.linalg.norm(d, axis=0)))
    u, w = mi.Float(rng.uniform(0, 1, n)), [mi.Float(rng.normal(size=n)) for _ in range(3)]

    def loss():
        out = render_rays(integ, o, d, u, ("full", "composite"), distortion=("full",))
        return (dr.sum(out["full"][0][0] * w[0] + out["full"][1] * w[1]) + dr.sum(out["composite"][0][2] * w[2])
                + 0.1 * dr.sum(out["distortion"]["full"]))
    params = mi.traverse(integ)
    for key in ("full.density", "full.color", "bg.density"):
        check_gradient(params, key, loss)


@pytest.mark.parametrize("at", [0.8, 1.7])  # scene z: in the inner (linear) region, and in the shell
def test_skipping_never_steps_over_a_thin_dense_feature(at):
    """A one-voxel-thick opaque sheet beyond every ray origin, occupancy cells 8 voxels wide: rays from many
    directions that cross it are stopped by it with skipping as without (the samples after a skip lie
    elsewhere on the ray, so the sheet's quadrature differs in the last digits)."""
    n = 129
    c = np.linspace(-2, 2, n)
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    sheet = np.abs(z - at) < 0.5 * (c[1] - c[0])  # one vertex layer
    density = np.where(sheet, 300.0, -20.0)[..., None]
    colour = np.zeros((n, n, n, 3))
    empty = field_dict(np.full((2, 2, 2, 1), -20.0), np.zeros((2, 2, 2, 3)), CUBE)
    integ = contracted(field_dict(density, colour, CUBE), empty, step=0.01)
    rng = np.random.default_rng(2)
    m = 2000
    d = np.column_stack([rng.uniform(-0.6, 0.6, (m, 2)), np.ones(m)])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o, dd, u = mi.Point3f(*rng.uniform(-0.2, 0.2, (3, m))), mi.Vector3f(*d.T), mi.Float(rng.uniform(0, 1, m))
    plain = np.array(render_rays(integ, o, dd, u, ("full",))["full"][1])
    integ.update_occupancy(16, 0.01)  # cells of 8 voxels
    assert integ.skip_length() > 4 * integ.step_size
    out = render_rays(integ, o, dd, u, ("full",))
    skipped = np.array(out["full"][1])
    assert plain.min() > 0.999 and skipped.min() > 0.999  # every ray crosses the sheet, and is stopped
    np.testing.assert_allclose(skipped, plain, atol=1e-3)
    everywhere = render_rays(contracted(field_dict(density, colour, CUBE), empty, step=0.01), o, dd, u, ("full",))
    assert np.array(out["evaluated"]).mean() < 0.5 * np.array(everywhere["evaluated"]).mean()


def haze_and_sheet(at=0.8, n=129):
    """A faint haze (optical depth 0.01 per voxel) through the cube and a one-voxel opaque sheet at scene
    z = ``at`` (None: none), with rays from near the origin that all cross it."""
    c = np.linspace(-2, 2, n)
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    voxel = c[1] - c[0]
    haze = np.log(np.expm1(0.01 / voxel))  # raw density of sigma = 0.01 / voxel (softplus)
    sheet = np.abs(z - at) < 0.5 * voxel if at is not None else np.zeros(z.shape, bool)
    density = np.where(sheet, 300.0, haze + 0.5 * np.sin(5 * x) * np.cos(4 * y))[..., None]
    colour = np.stack([np.sin(3 * x), np.cos(2 * y), np.full(x.shape, 0.5)], -1)
    rng = np.random.default_rng(3)
    m = 2000
    d = np.column_stack([rng.uniform(-0.6, 0.6, (m, 2)), np.ones(m)])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    rays = mi.Point3f(*rng.uniform(-0.2, 0.2, (3, m))), mi.Vector3f(*d.T), mi.Float(rng.uniform(0, 1, m))
    return field_dict(density, colour, CUBE), rays


@pytest.mark.parametrize("at", [0.8, 1.7])
def test_strides_cross_thin_haze_in_longer_steps_and_never_step_over_a_dense_feature(at):
    """Haze below the sparsest stride level and an opaque one-voxel sheet: with strides every ray is still
    stopped by the sheet, the haze in front of it renders within 2e-3, and the rays evaluate under half the
    samples (the haze crossed in steps of several voxels, the sheet's neighbourhood in the march's own)."""
    field, (o, d, u) = haze_and_sheet(at)
    empty = field_dict(np.full((2, 2, 2, 1), -20.0), np.zeros((2, 2, 2, 3)), CUBE)
    out = {}
    for strides in (False, True):
        integ = contracted(field, empty, step=0.01, strides=strides)
        integ.update_occupancy(128, 0.01)  # cells of one voxel, every one occupied by the haze
        out[strides] = render_rays(integ, o, d, u, ("full",))
    plain, strided = (np.array(out[s]["full"][1]) for s in (False, True))
    assert plain.min() > 0.999 and strided.min() > 0.999
    diff = np.array(out[True]["full"][0]) - np.array(out[False]["full"][0])
    assert np.abs(diff).max() < 2e-2 and abs(diff.mean()) < 1e-3  # a jittered estimate of the haze's colour
    assert np.array(out[True]["evaluated"]).mean() < 0.5 * np.array(out[False]["evaluated"]).mean()


def test_strides_gradients_match_finite_differences():
    """Through the strided haze (no sheet: no ray stops), the adjoint replays the primal's steps."""
    field, (o, d, u) = haze_and_sheet(None, n=33)
    integ = contracted(field, random_field(2, shape=(6, 6, 6), to_world=CUBE, scale=0.1), step=0.02, strides=True)
    integ.update_occupancy(32, 0.01)
    assert integ.plan(("full",)).strides  # some level steps further than the march
    n = 64
    o, d, u = mi.Point3f(*[np.array(a)[:n] for a in o]), mi.Vector3f(*[np.array(a)[:n] for a in d]), mi.Float(
        np.array(u)[:n])
    w = [mi.Float(np.random.default_rng(5).normal(size=n)) for _ in range(2)]

    def loss():
        out = render_rays(integ, o, d, u, ("full",))
        return dr.sum(out["full"][0][0] * w[0] + out["full"][1] * w[1])
    params = mi.traverse(integ)
    for key in ("full.density", "full.color"):
        check_gradient(params, key, loss)


def test_strides_need_a_contracted_space():
    with pytest.raises(Exception, match="strides need a contracted space"):
        mi.load_dict({"type": "voldis", "strides": True, "full": constant_field(1.0, [0, 0, 0], CUBE),
                      "bg": constant_field(1.0, [0, 0, 0], CUBE)})
