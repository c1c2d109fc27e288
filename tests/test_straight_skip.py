"""Straight rays jump over the rest of an empty occupancy cell: the same samples, fewer loop iterations.

A world-space scene of a few dense blobs in empty space, its occupancy grid on: rendering with the jumps
and with them disabled (every slot visited one by one, as before) gives bit-identical layers and evaluated
counts, and the same gradients (summed in another order), and a slot never lands past one it should sample."""
from types import SimpleNamespace

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import UNIT_BOX, field_dict, integrator

from mi_voldis.render import march
from mi_voldis.render.occupancy import Occupancy
from mi_voldis.render.rays import render_rays


def blobs(n=48):
    """Density: three Gaussian blobs in [-1, 1]^3, empty (-20 raw) elsewhere; colour varying."""
    c = np.linspace(-1, 1, n)
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    dens = np.full(x.shape, -20.0)
    for cx, cy, cz in ((-0.5, 0.2, 0.1), (0.4, -0.3, -0.4), (0.1, 0.5, 0.6)):
        dens = np.maximum(dens, 40.0 * np.exp(-((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / 0.02) - 20.0)
    colour = np.stack([np.sin(3 * x), np.cos(2 * y), x * z], -1)
    return field_dict(dens[..., None], colour, UNIT_BOX)


def rays(m=3000, seed=4):
    rng = np.random.default_rng(seed)
    o = rng.uniform(-1, 1, (m, 3)) * [1, 1, 0] + [0, 0, -3]
    target = rng.uniform(-0.8, 0.8, (m, 3))
    d = target - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return mi.Point3f(*o.T), mi.Vector3f(*d.T), mi.Float(rng.uniform(0, 1, m))


def render(monkeypatch, jump, grad=False):
    if not jump:  # every slot one by one: the cell's exit is where the slot already is
        monkeypatch.setattr(Occupancy, "exit_distance", lambda self, p, d: dr.zeros(mi.Float, dr.width(p)))
    integ = integrator(blobs(), field_dict(np.full((2, 2, 2, 1), -20.0), np.zeros((2, 2, 2, 3)), UNIT_BOX),
                       samples=4096, step_size=0.01)
    occupancy = integ.update_occupancy(12, 0.05)
    assert 0.02 < occupancy.fraction < 0.5
    params = mi.traverse(integ)
    o, d, u = rays()
    if grad:
        dr.enable_grad(params["full.density"])
        params.update()
    out = render_rays(integ, o, d, u, ("full",))
    result = [np.array(out["full"][0]), np.array(out["full"][1]), np.array(out["full"][2]), np.array(out["evaluated"])]
    if grad:
        dr.backward(dr.sum(out["full"][0][0] + 0.5 * out["full"][1]))
        result.append(np.array(dr.grad(params["full.density"])))
    monkeypatch.undo()
    return result


@pytest.mark.parametrize("grad", [False, True])
def test_jumping_over_empty_cells_gives_the_same_samples(monkeypatch, grad):
    jumped, visited = render(monkeypatch, True, grad), render(monkeypatch, False, grad)
    assert visited[1].max() > 0.5 and visited[3].mean() > 1  # rays meet the blobs
    for a, b in zip(jumped[:4], visited[:4]):
        np.testing.assert_array_equal(a, b)
    if grad:  # the same terms, scattered into the grid in another order
        np.testing.assert_allclose(jumped[4], visited[4], rtol=1e-5, atol=1e-6 * np.abs(visited[4]).max())


def test_the_next_slot_lands_at_the_first_slot_past_an_empty_cell():
    """One ray along +x through four cells one unit wide, only the third occupied, slots at
    t_j = (j + 1/4) / 10: from an empty cell the next slot is the first at or past its far face, from
    an occupied one the next; never past the ray's last slot."""
    occupancy = Occupancy([0, 0, 0], [4, 1, 1], np.array([[[False, False, True, False]]]))
    rays = march.Rays(o=None, d=None, o_s=mi.Point3f(0.0, 0.5, 0.5), d_s=mi.Vector3f(1.0, 0.0, 0.0),
                      t0=mi.Float(0.0), t1=mi.Float(4.0), hit=mi.Bool(True))
    path = march.Path.__new__(march.Path)  # the state sample() keeps, set by hand
    path.plan = SimpleNamespace(occupancy=occupancy, space=SimpleNamespace(is_curved=False))
    path.rays, path.u, path.n, path.dt = rays, mi.Float(0.25), 40, mi.Float(0.1)
    for j, expected in ((0, 10), (9, 10), (10, 20), (19, 20), (20, 21), (29, 30), (30, 40), (39, 40)):
        t = rays.t0 + (mi.Float(j) + path.u) * path.dt
        p = rays.o_s + t * rays.d_s
        assert int(path.next_slot(mi.UInt32(j), t, p, occupancy.lookup(p))[0]) == expected, j


def test_cells_of_one_voxel_skip_more_than_cells_of_four_for_the_same_image():
    """The blobs' 48^3 grid with occupancy cells of four voxels (12 cells) and of one (47): the finer
    grid leaves out only density below the threshold, so the image agrees to that (1e-3), and it
    evaluates fewer samples, every ray at most as many."""
    out = {}
    for cells in (12, 47):
        integ = integrator(blobs(), field_dict(np.full((2, 2, 2, 1), -20.0), np.zeros((2, 2, 2, 3)), UNIT_BOX),
                           samples=4096, step_size=0.01, occupancy_resolution=cells, occupancy_threshold=0.05)
        o, d, u = rays()
        r = render_rays(integ, o, d, u, ("full",))
        out[cells] = np.array(r["full"][0]), np.array(r["evaluated"])
    assert out[12][1].mean() > 1 and np.all(out[47][1] <= out[12][1]) and out[47][1].mean() < 0.8 * out[12][1].mean()
    np.testing.assert_allclose(out[47][0], out[12][0], atol=1e-3)
