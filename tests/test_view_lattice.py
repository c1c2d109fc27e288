"""Grey view dependence on a lattice of its own (``radiance_field``'s ``view``): the same field as the
harmonics at every vertex where the lattices agree, gradients against finite differences, exact degree
changes, round trips through files and checkpoints, one-line errors, and what fitting does with it
(the memory plan, the hull's clearing, progressive view dependence)."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import UNIT_BOX, integrator

from mi_voldis.field import bricks
from mi_voldis.field import state as field_state
from mi_voldis.field.spec import brick_field_dict
from mi_voldis.plugins.radiance_field import SH_Y0
from mi_voldis.render.rays import render_rays


def random_values(shape_zyx, channels, seed):
    return np.random.default_rng(seed).normal(size=shape_zyx + (channels,)).astype(np.float32)


def view_field(values, view, brick=4, **extra):
    """A ``radiance_field`` dict: density and RGB ``values`` (Z, Y, X, 4) in bricks, the gloss on ``view``."""
    return {**brick_field_dict(values[..., :1], values[..., 1:4], UNIT_BOX, brick=brick), "view": mi.TensorXf(view),
            **extra}


def directions(n, seed):
    return dr.normalize(mi.Vector3f(*np.random.default_rng(seed).normal(size=(3, n))))


def test_a_view_lattice_like_the_bricks_gives_the_harmonics_at_every_vertex():
    """Coefficients on a view lattice of the bricks' own shape are the grey degree-1 field with those
    coefficients at its vertices: the same density and colours at any point, from any direction."""
    fine = random_values((6, 7, 9), 7, seed=1)
    fine_field = mi.load_dict(brick_field_dict(fine[..., :1], fine[..., 1:], UNIT_BOX, brick=4))
    lattice = mi.load_dict(view_field(fine[..., :4], fine[..., 4:]))
    assert (lattice.sh_degree, lattice.grey, lattice.channels, lattice.view_shape) == (1, True, 4, (9, 7, 6))
    p = mi.Point3f(*np.random.default_rng(2).uniform(0, 1, (3, 400)))
    d = directions(400, 3)
    for a, b in zip(fine_field.eval_local(p, d), lattice.eval_local(p, d)):
        np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-5, atol=1e-6)


def test_one_coefficient_is_an_analytic_gloss():
    """Y_1^0 / Y_0 = sqrt(3) z: a coefficient k of it on a coarse lattice over a grey mean (logit 0) gives
    sigmoid(sqrt(3) k d_z) in direction d, wherever the point lies."""
    values = np.zeros((9, 9, 9, 4), np.float32)
    view = np.zeros((3, 2, 4, 3), np.float32)
    view[..., 1] = 0.7
    field = mi.load_dict(view_field(values, view))
    d = directions(64, 4)
    p = mi.Point3f(*np.random.default_rng(5).uniform(0, 1, (3, 64)))
    colour = np.array(field.eval_local(p, d)[1])
    want = 1 / (1 + np.exp(-np.sqrt(3) * 0.7 * np.array(d)[2]))
    np.testing.assert_allclose(colour, np.repeat(want[None], 3, 0), atol=1e-6)
    assert abs(np.sqrt(3) - 0.4886025119029199 / SH_Y0) < 1e-12  # Y_1^0's constant over Y_0's


def test_gradients_of_the_view_lattice_match_finite_differences():
    rng = np.random.default_rng(6)
    values = random_values((5, 6, 7), 4, seed=7)
    view = rng.normal(0, 1, (3, 4, 3, 3)).astype(np.float32)
    integ = integrator(view_field(values, view), view_field(values * 0.5, view), samples=24)
    params = mi.traverse(integ)
    n = 32
    o = mi.Point3f(*(rng.normal(size=(3, n)) * 3.0))
    d = dr.normalize(mi.Point3f(*rng.uniform(-0.5, 0.5, (3, n))) - o)
    u = mi.Float(rng.uniform(0, 1, n))
    layers = ("composite", "full", "bg", "fg")

    def loss():
        out = render_rays(integ, o, d, u, layers)
        return dr.sum(out["composite"][0][0] + 0.5 * out["full"][0][1] - out["fg"][0][2])
    dr.enable_grad(params["full.data"])
    params.update()
    dr.backward(loss())
    grad = np.array(dr.grad(params["full.data"])).reshape(-1, 4)
    dr.disable_grad(params["full.data"])
    rows = integ.fields["full"].layout.slots * 64
    assert np.abs(grad[rows:, 1:]).max() > 0 and (grad[rows:, 0] == 0).all()  # the density slot is unused
    base = np.array(params["full.data"])
    for j in np.argsort(-np.abs(grad[rows:, 1:]).ravel())[:4]:
        r, c = rows + j // 3, 1 + j % 3
        sums = []
        for sign in (1, -1):
            b = base.copy()
            b[r, c] += sign * 3e-3
            params["full.data"] = mi.TensorXf(b)
            params.update()
            with dr.suspend_grad():
                sums.append(float(np.array(loss())[0]))
        fd = (sums[0] - sums[1]) / 6e-3
        assert abs(fd - grad[r, c]) <= 0.02 * abs(fd) + 2e-3 * np.abs(grad).max(), (r, c, fd, grad[r, c])


def test_raising_to_a_view_lattice_and_back_is_exact():
    """Degree 0 -> grey degree 1 on a view lattice appends a lattice of zeros (the same renders), resampling
    keeps it, degree 0 again gives the bricks bit for bit; into harmonics at the vertices only via degree 0."""
    values = random_values((9, 9, 9), 4, seed=8)
    layout, data = bricks.from_dense(values, 4)
    state = field_state.FieldState(layout, mi.Float(data), 4, UNIT_BOX)
    raised = field_state.with_sh_degree(state, 1, True, view_resolution=5)
    assert (raised.sh_degree, raised.grey, raised.width, raised.view_shape) == (1, True, 4, (5, 5, 5))
    assert dr.width(raised.data) == (raised.vertices + 125) * 4 and not raised.view_values().any()
    p, d = mi.Point3f(*np.random.default_rng(9).uniform(0, 1, (3, 300))), directions(300, 10)
    for x, y in zip(*(mi.load_dict(s.plugin()).eval_local(p, d) for s in (state, raised))):
        np.testing.assert_array_equal(np.array(x), np.array(y))
    view = np.random.default_rng(11).normal(size=(5, 5, 5, 3)).astype(np.float32)
    raised = raised.with_bricks(raised.bricks_data())  # the same, through the bricks' own setter
    rows = np.array(raised.data).reshape(-1, 4)
    rows[raised.vertices:, 1:] = view.reshape(-1, 3)
    raised = raised.with_data(mi.Float(rows.ravel()))
    fine = field_state.resample(raised, (13, 13, 13))
    np.testing.assert_array_equal(fine.view_values(), view)
    np.testing.assert_array_equal(np.array(field_state.with_sh_degree(raised, 0).data), np.array(state.data))
    assert field_state.with_sh_degree(raised, 1, True, 5) is raised
    with pytest.raises(ValueError, match="through degree 0"):
        field_state.with_sh_degree(raised, 1, True)
    with pytest.raises(ValueError, match="through degree 0"):
        field_state.with_sh_degree(field_state.with_sh_degree(state, 1, True), 1, True, 5)


def test_the_view_lattice_round_trips_through_grid_files_checkpoints_and_scene_files(tmp_path):
    from mi_voldis.fit.state import FitState
    from mi_voldis.optim.adam import Adam
    from mi_voldis.scene import write_scene
    values = random_values((9, 9, 9), 4, seed=12)
    layout, data = bricks.from_dense(values, 4)
    state = field_state.with_sh_degree(field_state.FieldState(layout, mi.Float(data), 4, UNIT_BOX, 2.0, True),
                                       1, True, view_resolution=6)
    rows = np.array(state.data).reshape(-1, 4)
    rows[state.vertices:, 1:] = np.random.default_rng(13).normal(size=(state.view_vertices, 3))
    state = state.with_data(mi.Float(rows.ravel()))
    fit = FitState(np.zeros(3), np.ones(3), Adam({}, 0.9, 0.99), fields={"full": state})
    fit.save(str(tmp_path / "state.npz"), "full", 0)
    back = FitState.load(str(tmp_path / "state.npz"), Adam({}, 0.9, 0.99)).fields["full"]
    assert back.view_shape == (6, 6, 6)
    np.testing.assert_array_equal(np.array(back.data), np.array(state.data))
    write_scene(str(tmp_path), {"full": state, "bg": mi.load_dict(state.plugin())}, {"samples": 8})
    grid = np.load(tmp_path / "full_grid.npz")
    assert grid["data"].shape[-1] == 4 and grid["view"].shape == (6, 6, 6, 3)
    scene = mi.load_file(str(tmp_path / "scene.xml"))
    for role in ("full", "bg"):
        field = scene.integrator().fields[role]
        assert field.view_shape == (6, 6, 6) and field.sh_gate
        np.testing.assert_array_equal(np.array(field.packed), np.array(state.data))


@pytest.mark.parametrize("change, message", [
    (lambda v: {"view": mi.TensorXf(np.zeros((3, 3, 3, 2), np.float32))}, r"shape \(Z, Y, X, 3\)"),
    (lambda v: {"view": mi.TensorXf(np.zeros((1, 3, 3, 3), np.float32))}, "at least 2 vertices per axis"),
    (lambda v: {"view": mi.TensorXf(np.full((2, 2, 2, 3), np.nan, np.float32))}, "NaN or Inf"),
])
def test_bad_view_lattices_are_refused_in_one_line(change, message):
    values = random_values((5, 5, 5), 4, seed=14)
    props = {**brick_field_dict(values[..., :1], values[..., 1:], UNIT_BOX, brick=4), **change(values)}
    with pytest.raises(RuntimeError, match=message):
        mi.load_dict(props)


def test_a_view_lattice_needs_rgb_bricks_and_a_brick_grid(tmp_path):
    values = random_values((5, 5, 5), 7, seed=15)
    view = mi.TensorXf(np.zeros((2, 2, 2, 3), np.float32))
    with pytest.raises(RuntimeError, match="needs RGB colour at the brick vertices"):
        mi.load_dict({**brick_field_dict(values[..., :1], values[..., 1:], UNIT_BOX, brick=4), "view": view})
    with pytest.raises(RuntimeError, match="needs a brick grid"):
        mi.load_dict({"type": "radiance_field", "density": mi.TensorXf(values[..., :1]),
                      "color": mi.TensorXf(values[..., 1:4]), "view": view})
    np.savez(tmp_path / "bad_grid.npz", table=np.ones((1, 1, 1), np.uint32), data=values.reshape(-1, 7)[:64],
             vertices=np.array([4, 4, 4]), brick=np.array(4), view=np.zeros((2, 2, 3), np.float32))
    with pytest.raises(RuntimeError, match=r"bad_grid.npz: the view lattice must have shape \(Z, Y, X, 3\)"):
        mi.load_dict({"type": "radiance_field", "grid": str(tmp_path / "bad_grid.npz")})


def test_clearing_view_dependence_clears_the_view_vertices_inside_a_region_and_no_others():
    values = random_values((17, 17, 17), 4, seed=16)
    layout, data = bricks.from_dense(values, 8)
    state = field_state.with_sh_degree(field_state.FieldState(layout, mi.Float(data), 4, UNIT_BOX), 1, True, 5)
    state = state.with_data(dr.select(dr.arange(mi.UInt32, dr.width(state.data)) >= state.vertices * 4, 1.0,
                                      state.data))
    local, real = field_state.vertex_local(state)
    x = np.array(local)

    def cleared(region):
        out = field_state.without_view_dependence(state, real & mi.Bool(region))
        np.testing.assert_array_equal(np.array(out.bricks_data()), np.array(state.bricks_data()))
        view = out.view_values()  # (Z, Y, X, 3): 1 where kept
        assert (view[..., 1:] == view[..., :1]).all()
        return view[..., 0] == 0

    # brick vertices 0..4 of 16 along each axis (x <= 0.25): view vertices 0 and 0.25 of 0, 0.25, ..., 1
    corner = cleared(np.all(x < 0.3, axis=0))
    expected = np.zeros((5, 5, 5), bool)
    expected[:2, :2, :2] = True
    np.testing.assert_array_equal(corner, expected)
    # x, y, z in [0.3, 0.45]: inside one view cell, on no view vertex; the view vertices around it keep their gloss
    assert not cleared(np.all((x > 0.3) & (x < 0.45), axis=0)).any()
    # brick vertices 0..3 (x < 0.2): view vertex 0.25 is brick vertex 4, outside the region, and keeps its gloss
    np.testing.assert_array_equal(cleared(np.all(x < 0.2, axis=0)), np.pad(np.ones((1, 1, 1), bool), (0, 4)))


def test_the_memory_plan_counts_a_view_lattice_once_and_bricks_at_degree_zero():
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.schedule import BYTES_PER_VERTEX, affordable_vertices
    grey = FitConfig(sh_color="grey", max_memory_gib=4.0)
    zero = affordable_vertices(grey, 10 ** 6, 0)
    assert affordable_vertices(grey, 10 ** 6, 1) == pytest.approx(zero - 64 ** 3)
    assert affordable_vertices(grey.replace(sh_view_resolution=None), 10 ** 6, 1) == pytest.approx(zero / 2)
    assert affordable_vertices(grey.replace(sh_color="rgb"), 10 ** 6, 1) == pytest.approx(zero / 4)
    assert BYTES_PER_VERTEX > 0


def test_an_all_zero_view_lattice_is_not_read_and_changes_nothing():
    """Before progressive view dependence's onset fitting turns the lattice's lookups off
    (``view_enabled``), which :func:`~mi_voldis.fit.problem.view_lattice_zero` allows: an all-0 lattice's
    lookups add 0. The switch gives the same values there, and the gloss-free mean where the lattice holds
    a gloss."""
    from mi_voldis.fit.problem import view_lattice_zero
    values = random_values((9, 9, 9), 4, seed=17)
    p = mi.Point3f(*np.random.default_rng(18).uniform(0, 1, (3, 300)))
    d = directions(300, 19)
    zero = mi.load_dict(view_field(values, np.zeros((3, 4, 5, 3), np.float32)))
    glossy = mi.load_dict(view_field(values, random_values((3, 4, 5), 3, seed=20)))
    assert view_lattice_zero(zero) and not view_lattice_zero(glossy)
    assert not view_lattice_zero(mi.load_dict(brick_field_dict(values[..., :1], values[..., 1:], UNIT_BOX, brick=4)))
    on = [np.array(v) for v in zero.eval_local(p, d)]
    zero.view_enabled = glossy.view_enabled = False
    for a, b in zip(on, zero.eval_local(p, d)):
        np.testing.assert_array_equal(a, np.array(b))
    mean = mi.load_dict(brick_field_dict(values[..., :1], values[..., 1:], UNIT_BOX, brick=4))
    for a, b in zip(mean.eval_local(p, d), glossy.eval_local(p, d)):
        np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-6, atol=1e-7)


def test_the_benchmark_times_the_same_bricks_with_and_without_a_view_lattice():
    """``bench.py``'s throughput rows: the "view" representation is the "bricks" one (same seed, same values)
    plus a VIEW_RESOLUTION^3 lattice, and the report gives the seconds of its training step over theirs."""
    from mi_voldis.bench import report, throughput
    plain = throughput.make_integrator(8, 16, representation="bricks")
    view = throughput.make_integrator(8, 16, representation="view")
    for role in ("full", "bg"):
        a, b = plain.fields[role], view.fields[role]
        assert a.view_shape is None and b.view_shape == (throughput.VIEW_RESOLUTION,) * 3
        bricks_rows = a.rows * a.width
        np.testing.assert_array_equal(np.array(a.packed), np.array(b.packed)[:bricks_rows])
    assert throughput.step_functions(8, 16, 64, representation="view")["train"](0) > 0
    timed = {"forward": {"msps": 1.0, "seconds": 1.0}, "train": {"msps": 1.0, "seconds": 0.2}}
    row = {"resolution": 8, "samples": 16, "batch": 64, "rays": "random", "voldis": timed,
           "voldis_view": {**timed, "train": {"msps": 1.0, "seconds": 0.25}}}
    lines = report._throughput({"bandwidth": {"drjit_gbs": 10.0, "numpy_gbs": 5.0}, "throughput": [row]})
    assert lines[-2].split(" | ")[9] == "1.25x"
