"""Sparse brick grids: the same interpolant as the dense grid they store, exact round trips, carving
and resampling, neighbours, files, and gradients through the plugin."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import UNIT_BOX, axis_rays, check_gradient, field_dict, integrator

from mi_voldis.field import bricks, grid
from mi_voldis.field import state as field_state
from mi_voldis.field.spec import brick_field_dict
from mi_voldis.render.rays import render_rays


def random_values(shape_zyx, channels=4, seed=0):
    return np.random.default_rng(seed).normal(size=shape_zyx + (channels,)).astype(np.float32)


@pytest.mark.parametrize("brick", [2, 4, 8])
def test_same_interpolant_as_the_dense_grid(brick):
    values = random_values((7, 11, 13))
    layout, data = bricks.from_dense(values, brick)
    np.testing.assert_array_equal(bricks.to_dense(data, layout, 4), values)
    p = mi.Point3f(*np.random.default_rng(1).uniform(-0.1, 1.1, (3, 500)))  # outside: clamped alike
    dense = grid.pack([mi.TensorXf(values[..., :1]), mi.TensorXf(values[..., 1:])])
    a = bricks.trilinear(mi.Float(data), layout, 4, 4, p)
    b = grid.trilinear(dense, (13, 11, 7), 4, 4, p)
    for x, y in zip(a, b):
        np.testing.assert_allclose(np.array(x), np.array(y), rtol=1e-6, atol=1e-6)


def test_device_coordinates_and_neighbours_match_the_lattice():
    values = random_values((9, 6, 10), seed=2)
    keep = np.zeros(bricks.counts((10, 6, 9), 4)[::-1], bool)
    keep[0, 0, 0] = keep[1, 1, 2] = keep[2, 0, 1] = True
    layout, data = bricks.from_dense(values, 4, keep)
    coords, inside = layout.vertex_coords()
    (i, j, k), dev_inside = layout.device_coords()
    np.testing.assert_array_equal(np.array(dev_inside), inside)
    np.testing.assert_array_equal(np.stack([np.array(i), np.array(j), np.array(k)], -1)[inside], coords[inside])
    state = field_state.FieldState(layout, mi.Float(data), 4, UNIT_BOX)
    nb = [np.array(a) for a in field_state.neighbour_vertices(state)]
    where = {tuple(c): n for n, c in enumerate(coords) if inside[n]}
    for n in np.flatnonzero(inside)[::7]:
        for axis in range(3):
            for s, step in enumerate((-1, 1)):
                c = coords[n].copy()
                c[axis] += step
                if not 0 <= c[axis] < layout.shape[axis]:
                    want = n  # Neumann border: itself
                else:
                    want = where.get(tuple(c))
                    if want is None:  # in an unallocated brick: the empty brick's vertex of that place
                        b = layout.brick
                        want = ((c[2] % b) * b + c[1] % b) * b + c[0] % b
                assert nb[2 * axis + s][n] == want
    lazy = field_state.neighbour_vertices(state, evaluate=False)  # the same tables, as expressions
    for a, b in zip(lazy, nb):
        np.testing.assert_array_equal(np.array(a), b)


def test_resampling_to_a_finer_lattice_keeps_the_field():
    values = random_values((10, 10, 10), seed=3)
    layout, data = bricks.from_dense(values, 4)
    state = field_state.FieldState(layout, mi.Float(data), 4, UNIT_BOX)
    fine = field_state.resample(state, (19, 19, 19))  # every old vertex is a new one: same interpolant
    p = mi.Point3f(*np.random.default_rng(4).uniform(0, 1, (3, 800)))
    for x, y in zip(bricks.trilinear(state.data, layout, 4, 4, p), bricks.trilinear(fine.data, fine.layout, 4, 4, p)):
        np.testing.assert_allclose(np.array(x), np.array(y), atol=2e-5)


@pytest.mark.parametrize("grey", [False, True])
def test_raising_the_degree_and_back_is_exact(grey):
    """Degree 0 -> 1 (RGB or grey harmonics) appends zero coefficients, which render the same colours, and
    back to 0 gives the same values bit for bit; grey and RGB harmonics do not convert into each other."""
    values = random_values((9, 9, 9), seed=5)
    layout, data = bricks.from_dense(values, 4)
    state = field_state.FieldState(layout, mi.Float(data), 4, UNIT_BOX)
    raised = field_state.with_sh_degree(state, 1, grey)
    assert (raised.sh_degree, raised.grey, raised.width) == (1, grey, 8 if grey else 16)
    np.testing.assert_array_equal(np.array(field_state.with_sh_degree(raised, 0).data), np.array(state.data))
    p = mi.Point3f(*np.random.default_rng(6).uniform(0, 1, (3, 300)))
    d = dr.normalize(mi.Vector3f(*np.random.default_rng(7).normal(size=(3, 300))))
    low, high = (mi.load_dict(s.plugin()).eval_local(p, d) for s in (state, raised))
    for x, y in zip(low, high):
        np.testing.assert_array_equal(np.array(x), np.array(y))
    with pytest.raises(ValueError, match="through degree 0"):
        field_state.with_sh_degree(raised, 1, not grey)


def test_the_gate_travels_with_the_field_through_edits_checkpoints_and_scene_files(tmp_path):
    """A field's ``sh_gate`` survives the operations that derive one field from another (degree changes,
    resampling, new values), a checkpoint and a scene file; a checkpoint or scene written before the gate
    existed loads ungated."""
    from mi_voldis.fit.state import FitState
    from mi_voldis.optim.adam import Adam
    from mi_voldis.scene import save_any_field
    values = random_values((9, 9, 9), seed=8)
    layout, data = bricks.from_dense(values, 4)
    state = field_state.with_sh_degree(field_state.FieldState(layout, mi.Float(data), 4, UNIT_BOX, 2.0, True), 1, True)
    derived = [state, field_state.resample(state, (13, 13, 13)), state.with_data(dr.copy(state.data)),
               field_state.without_view_dependence(state, mi.Float(1.0))]
    assert all(f.sh_gate and f.density_scale == 2.0 for f in derived)
    assert mi.load_dict(state.plugin()).sh_gate
    fit = FitState(np.zeros(3), np.ones(3), Adam({}, 0.9, 0.99), fields={"full": state})
    fit.save(str(tmp_path / "state.npz"), "full", 0)
    assert FitState.load(str(tmp_path / "state.npz"), Adam({}, 0.9, 0.99)).fields["full"].sh_gate
    old = np.load(tmp_path / "state.npz", allow_pickle=False)
    np.savez(tmp_path / "old.npz", **{k: old[k] for k in old.files if not k.endswith("sh_gate")})
    assert not FitState.load(str(tmp_path / "old.npz"), Adam({}, 0.9, 0.99)).fields["full"].sh_gate
    for gate in (True, False):
        body = save_any_field(str(tmp_path), f"f{gate}", mi.load_dict({**state.plugin(), "sh_gate": gate}))
        assert ('name="sh_gate"' in body) == gate  # absent where false: files from before the gate read the same


@pytest.mark.parametrize("grey", [False, True])
def test_view_dependence_cleared_in_a_region_and_black_from_every_view_when_empty(grey):
    """``without_view_dependence`` zeroes the coefficients after the mean colour at the region's vertices
    alone; an empty vertex is black from every direction (its view-dependent coefficients are 0)."""
    values = random_values((9, 9, 9), seed=8)
    layout, data = bricks.from_dense(values, 4)
    field = field_state.with_sh_degree(field_state.FieldState(layout, mi.Float(data), 4, UNIT_BOX), 1, grey)
    n = field.vertices
    field = field_state.FieldState(field.layout, mi.Float(np.random.default_rng(9).normal(
        size=n * field.width).astype(np.float32)), field.channels, UNIT_BOX)
    region = np.random.default_rng(10).random(n) < 0.3
    out = np.array(field_state.without_view_dependence(field, mi.Bool(region)).data).reshape(n, field.width)
    before = np.array(field.data).reshape(n, field.width)
    assert (out[region, 4:] == 0).all()
    np.testing.assert_array_equal(out[region, :4], before[region, :4])
    np.testing.assert_array_equal(out[~region], before[~region])
    empty = bricks.empty_values(field.width, field.channels)
    assert empty[0] == bricks.EMPTY_DENSITY and (empty[1:4] == bricks.EMPTY_COLOR).all() and (empty[4:] == 0).all()
    vertex = mi.load_dict(field_state.FieldState(layout, mi.Float(np.tile(empty, layout.slots * 64)),
                                                 field.channels, UNIT_BOX).plugin())
    d = dr.normalize(mi.Vector3f(*np.random.default_rng(11).normal(size=(3, 100))))
    colour = np.array(vertex.eval_local(mi.Point3f(0.5, 0.5, 0.5), d)[1])
    assert colour.max() < 1e-4  # sigmoid(-10): black, whatever the direction


def test_carving_keeps_needed_bricks_and_a_margin():
    layout, data = bricks.from_dense(random_values((24, 24, 24), seed=5), 4)
    state = field_state.FieldState(layout, mi.Float(data), 4, UNIT_BOX)
    needed = np.zeros(layout.table.shape, bool)
    needed[2, 3, 4] = True
    keep = field_state.carve(state, needed)
    assert keep.sum() == 27 and keep[1:4, 2:5, 3:6].all()
    carved = field_state.resample(state, keep=keep)
    assert carved.layout.allocated == 27
    # kept bricks hold the same values; the others are the empty brick
    dense = bricks.to_dense(np.array(carved.data), carved.layout, 4)
    b = 4
    np.testing.assert_allclose(dense[2 * b:3 * b, 3 * b:4 * b, 4 * b:5 * b],
                               bricks.to_dense(data, layout, 4)[2 * b:3 * b, 3 * b:4 * b, 4 * b:5 * b], atol=1e-5)
    assert (dense[0:b, 0:b, 0:b, 0] == bricks.EMPTY_DENSITY).all()


def test_brick_field_renders_and_differentiates_like_the_dense_one():
    rng = np.random.default_rng(6)
    d, c = rng.normal(0, 1, (6, 5, 7, 1)), rng.normal(0, 1, (6, 5, 7, 3))
    dense = integrator(field_dict(d, c, UNIT_BOX), field_dict(d * 0.5, c, UNIT_BOX), samples=24)
    sparse = integrator(brick_field_dict(d, c, UNIT_BOX, brick=4), brick_field_dict(d * 0.5, c, UNIT_BOX, brick=4),
                        samples=24)
    o, dd, u = axis_rays(40, seed=2)
    layers = ("composite", "full", "bg", "fg")
    a, b = render_rays(dense, o, dd, u, layers), render_rays(sparse, o, dd, u, layers)
    for layer in layers:
        for x, y in zip(a[layer], b[layer]):
            np.testing.assert_allclose(np.array(x), np.array(y), rtol=1e-5, atol=1e-6)
    params = mi.traverse(sparse)

    def loss():
        out = render_rays(sparse, o, dd, u, layers)
        return dr.sum(out["composite"][0][0]) + dr.sum(out["full"][1]) + dr.sum(out["fg"][0][1])
    grad = check_gradient(params, "full.data", loss)
    assert np.abs(grad.reshape(-1, 4)[64:]).max() > 0 and np.abs(grad.reshape(-1, 4)[:64]).max() == 0


def test_grid_files_round_trip(tmp_path):
    from mi_voldis.io.scene_xml import save_grid, write_scene
    values = random_values((6, 9, 10), seed=7)
    keep = np.zeros(bricks.counts((10, 9, 6), 4)[::-1], bool)
    keep[0, 1, 1] = keep[1, 2, 0] = True
    layout, data = bricks.from_dense(values, 4, keep)
    body = save_grid(str(tmp_path), "full", layout, data.reshape(-1, 4)[64:], UNIT_BOX)
    write_scene(str(tmp_path / "scene.xml"), {"full": body, "bg": body}, {"samples": 8})
    field = mi.load_file(str(tmp_path / "scene.xml")).integrator().fields["full"]
    assert field.layout.allocated == 2 and field.shape == (10, 9, 6)
    np.testing.assert_array_equal(np.array(field.packed), data)
    np.testing.assert_allclose(field.to_world, UNIT_BOX, atol=1e-6)
    (tmp_path / "bad_grid.npz").write_bytes(b"nope")
    with pytest.raises(RuntimeError, match="bad_grid.npz: not a brick grid file"):
        mi.load_dict({"type": "radiance_field", "grid": str(tmp_path / "bad_grid.npz")})
