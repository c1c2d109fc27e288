"""The adjoint's replay from recorded lookup values (march.Record) against replay by reading the grids."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import axis_rays, integrator, random_field

from mi_voldis.render import march
from mi_voldis.render.rays import render_rays

LAYERS = ("composite", "full", "bg", "fg")


def gradients(integ, keys, rays=None):
    """Gradients of a random linear functional of every layer's RGB and alpha (on ``rays``, default 48
    rays along +z)."""
    params = mi.traverse(integ)
    for key in keys:
        dr.enable_grad(params[key])
    params.update()
    o, d, u = rays or axis_rays(48, seed=3)
    out = render_rays(integ, o, d, u, layers=LAYERS)
    rng = np.random.default_rng(7)
    loss = sum(dr.sum(out[lay][0][c] * mi.Float(rng.normal(size=48))) for lay in LAYERS for c in range(3))
    loss += sum(dr.sum(out[lay][1] * mi.Float(rng.normal(size=48))) for lay in LAYERS)
    dr.backward(loss)
    return {key: np.array(dr.grad(params[key])) for key in keys}


@pytest.mark.parametrize("channels", [3, 12])
def test_recorded_replay_equals_reading_the_grids(monkeypatch, channels):
    """A moved foreground makes four lookups (full and bg at p and at T^-1 p); SH degree 1 makes the
    record 16 floats wide. Recording changes where the replay's values come from, not the gradient."""
    def make():
        return integrator(random_field(1, channels=channels), random_field(2, channels=channels, scale=0.5),
                          samples=20, fg_to_world=mi.ScalarTransform4f().translate([0.2, 0.1, 0.0]))
    assert len(make().plan(LAYERS).lookups) == 4
    keys = ("full.density", "full.color", "bg.density", "bg.color")
    recorded = gradients(make(), keys)
    monkeypatch.setattr(march, "RECORD_BYTES", 0)  # no record fits: the replay reads the grids
    reread = gradients(make(), keys)
    for key in keys:
        assert np.abs(recorded[key]).max() > 0, key
        np.testing.assert_allclose(recorded[key], reread[key], rtol=1e-5, atol=1e-6 * np.abs(reread[key]).max())


def test_record_layout_and_budget(monkeypatch):
    integ = integrator(random_field(1), random_field(2), samples=8)
    plan = integ.plan(("full", "bg"))
    o, d, _ = axis_rays(10)
    rays = march.prepare_rays(plan, o, d)
    record = march.new_record(plan, rays)
    assert record is not None and march.Record.size(plan, 10, 8) == 4 * 10 * 8 * 4 * len(plan.lookups)
    # sample i of ray r at slot i * rays + r: written values come back for the same (i, r)
    values = {lk.key: [mi.Float(np.arange(10) + 100.0 * k + 1000.0 * j) for k in range(4)]
              for j, lk in enumerate(plan.lookups)}
    record.write(mi.UInt32(5), values, True)
    back = record.read(mi.UInt32(5), True)
    for key, v in values.items():
        for k in range(4):
            assert np.array_equal(np.array(back[key][k]), np.array(v[k]))
    monkeypatch.setattr(march, "RECORD_BYTES", march.Record.size(plan, 10, 8) - 1)
    assert march.new_record(plan, rays) is None


def test_mitsuba_render_adjoint_replays_the_record(monkeypatch):
    """mi.render's adjoint goes through the same march driver as fitting: its primal keeps a record,
    and the gradients equal those of a replay that reads the grids."""
    from helpers import ortho_scene

    def grads():
        scene = ortho_scene({"type": "voldis", "samples": 12, "full": random_field(3), "bg": random_field(4)},
                            size=6, spp=2)
        params = mi.traverse(scene)
        dr.enable_grad(params["integrator.full.density"])
        params.update()
        image = mi.render(scene, params, seed=1)
        dr.backward(dr.sum(image.array * mi.Float(np.random.default_rng(2).normal(size=dr.width(image.array)))))
        return np.array(dr.grad(params["integrator.full.density"]))

    made = []
    original = march.new_record
    monkeypatch.setattr(march, "new_record", lambda plan, rays: made.append(1) or original(plan, rays))
    recorded = grads()
    assert made, "the primal of mi.render's adjoint kept no record"
    monkeypatch.setattr(march, "RECORD_BYTES", 0)
    reread = grads()
    assert np.abs(recorded).max() > 0
    np.testing.assert_allclose(recorded, reread, rtol=1e-5, atol=1e-6 * np.abs(reread).max())


def test_adjoint_order_is_by_the_primal_iterations():
    assert march.adjoint_order(np.array([5, 2, 9, 2], np.uint32)).tolist() == [1, 3, 0, 2]


def test_the_adjoint_replays_rays_in_order_of_length_with_the_same_gradient(monkeypatch):
    """The adjoint replays the batch's rays sorted by how many iterations each took (SIMD packets of rays of
    like length): the gradient is the one of the rays replayed as marched, to rounding, with and without a
    record (whose slots each reordered ray reads as its own)."""
    calls = []

    def recorded_order(iterations):
        order = march.adjoint_order.__wrapped__(iterations)
        calls.append(order)
        return order

    recorded_order.__wrapped__ = march.adjoint_order
    keys = ("full.density", "full.color", "bg.density", "bg.color")

    def make():  # samples every 0.05: each ray as many as its path through the box holds
        return integrator(random_field(1), random_field(2, scale=0.5), samples=64, step_size=0.05,
                          fg_to_world=mi.ScalarTransform4f().translate([0.2, 0.1, 0.0]))

    rng = np.random.default_rng(4)
    start = np.column_stack([rng.uniform(-1.5, 1.5, (48, 2)), np.full(48, -3.0)])
    d = rng.uniform(-1, 1, (48, 3)) - start
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    rays = mi.Point3f(*start.T), mi.Vector3f(*d.T), mi.Float(rng.uniform(0, 1, 48))

    for record in (march.RECORD_BYTES, 0):
        monkeypatch.setattr(march, "RECORD_BYTES", record)
        monkeypatch.setattr(march, "adjoint_order", recorded_order)
        sorted_replay = gradients(make(), keys, rays)
        assert calls and not np.array_equal(calls[-1], np.arange(len(calls[-1])))  # the rays were reordered
        monkeypatch.setattr(march, "adjoint_order", lambda iterations: None)  # replayed as marched
        as_marched = gradients(make(), keys, rays)
        for key in keys:
            assert np.abs(as_marched[key]).max() > 0, key
            np.testing.assert_allclose(sorted_replay[key], as_marched[key], rtol=1e-5,
                                       atol=1e-6 * np.abs(as_marched[key]).max())


def test_a_training_step_marches_its_primal_once():
    """Forward and backward of render_rays with the distortion loss (as fitting runs them): the primal loop
    runs in one kernel, and the adjoint's kernel reads its sums instead of marching the primal again."""
    integ = integrator(random_field(1), random_field(2), samples=20)
    params = mi.traverse(integ)
    dr.enable_grad(params["full.density"])
    params.update()
    o, d, u = axis_rays(48, seed=3)

    def step():
        out = render_rays(integ, o, d, u, layers=("full",), distortion=("full",))
        dr.backward(dr.sum(out["full"][1]) + dr.sum(out["distortion"]["full"]))
        dr.eval(dr.grad(params["full.density"]))

    irs = kernels(step)
    assert sum("voldis adjoint" in ir for ir in irs) == 1
    assert sum("voldis primal" in ir for ir in irs) == 1


def kernels(run):
    """The IR of every kernel Dr.Jit compiles or launches while ``run()`` runs."""
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # clears it
        run()
        return [e["ir"].getvalue() if hasattr(e["ir"], "getvalue") else str(e["ir"])
                for e in dr.kernel_history() if e.get("ir") is not None]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)


def test_mitsuba_render_adjoint_marches_no_primal_inside_it():
    """mi.render's adjoint (``render_backward``) marches the primal once more for its record, as Mitsuba's
    PRB integrators do, and its adjoint kernel reads those sums instead of marching the primal a third time."""
    from helpers import ortho_scene

    scene = ortho_scene({"type": "voldis", "samples": 12, "full": random_field(3), "bg": random_field(4)},
                        size=6, spp=2)
    params = mi.traverse(scene)
    dr.enable_grad(params["integrator.full.density"])
    params.update()

    def render_and_backward():
        image = mi.render(scene, params, seed=1)
        dr.backward(dr.sum(image.array))
        dr.eval(dr.grad(params["integrator.full.density"]))

    irs = kernels(render_and_backward)
    adjoint = [ir for ir in irs if "voldis adjoint" in ir]
    assert len(adjoint) == 1
    assert "voldis primal" not in adjoint[0]
    assert sum("voldis primal" in ir for ir in irs) == 2  # the image's, and the record's for the adjoint
