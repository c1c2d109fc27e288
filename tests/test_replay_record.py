"""The adjoint's replay from recorded lookup values (march.Record) against replay by reading the grids."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import axis_rays, integrator, random_field

from mi_voldis.render import march
from mi_voldis.render.rays import render_rays

LAYERS = ("composite", "full", "bg", "fg")


def gradients(integ, keys):
    """Gradients of a random linear functional of every layer's RGB and alpha."""
    params = mi.traverse(integ)
    for key in keys:
        dr.enable_grad(params[key])
    params.update()
    o, d, u = axis_rays(48, seed=3)
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
