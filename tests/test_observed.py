"""Learning rates per brick by the training views that observe it (mi_voldis.fit.observed) and Adam's
per-element step scales."""
import mitsuba as mi
import numpy as np

from mi_voldis.cameras import Camera, look_at
from mi_voldis.field.state import new_field
from mi_voldis.fit.observed import brick_centres, brick_views, view_rate_scale
from mi_voldis.optim.adam import Adam
from mi_voldis.space import SceneSpace


def field_over_unit_box():
    """A 16^3 field over [-1, 1]^3 in bricks of 8: eight bricks, one per octant."""
    return new_field(np.full(3, -1.0), np.full(3, 1.0), 16, 0, -5.0, 1.0, brick=8)


def test_brick_centres_are_the_octants_middles():
    f = field_over_unit_box()
    centres = brick_centres(f)
    assert len(centres) == 8
    # vertices 0..7 and 8..15 of 16 over [-1, 1]: the middles at lattice 3.5 and 11.5 of 15
    np.testing.assert_allclose(np.sort(np.unique(centres[:, 0])), [-1 + 2 * 3.5 / 15, -1 + 2 * 11.5 / 15])


def test_views_count_the_cameras_whose_image_holds_the_brick_and_scale_the_rates():
    f, space = field_over_unit_box(), SceneSpace("world")
    centres = brick_centres(f)
    right = -1 + 2 * 11.5 / 15  # the +x bricks' centre
    # the wide camera holds every brick, the one behind faces away, the narrow one holds the bricks near x = right
    wide = Camera(look_at((0.0, 0.0, 6.0), (0.0, 0.0, 0.0)), fov_x=60.0, width=32, height=32)
    behind = Camera(look_at((0.0, 0.0, -6.0), (0.0, 0.0, -12.0)), fov_x=60.0, width=32, height=32)  # faces away
    narrow = Camera(look_at((right, right, 6.0), (right, right, 0.0)), fov_x=8.0, width=32, height=32)
    counts = brick_views(space, f, [wide, behind, narrow])
    assert counts[0] == 0 and len(counts) == 9
    # the narrow camera's square frustum, 8 degrees across, about the line x = y = right
    half = (6.0 - centres[:, 2]) * np.tan(np.radians(4.0))
    in_narrow = np.all(np.abs(centres[:, :2] - right) < half[:, None], axis=1)
    np.testing.assert_array_equal(counts[1:], 1 + in_narrow)
    assert in_narrow.sum() == 2  # the two bricks at x = y = right, z = -+ right
    for power in (1.0, 0.5):
        scale = np.array(view_rate_scale(space, f, [wide, behind, narrow], power))
        per_vertex = scale.reshape(-1, 8 ** 3 * f.width)
        assert np.all(per_vertex == per_vertex[:, :1])  # one value per brick
        np.testing.assert_allclose(per_vertex[:, 0], np.r_[0.0, (counts[1:] / 2) ** power], rtol=1e-6)
    # n_ref the median count (1: six bricks seen once, two twice): no brick is seen by fewer, all step at 1
    median = np.array(view_rate_scale(space, f, [wide, behind, narrow], 1.0, quantile=0.5)).reshape(9, -1)[:, 0]
    np.testing.assert_array_equal(median, np.r_[0.0, np.ones(8)])
    # n_ref the 80% quantile, between 1 and 2: the bricks seen once step at 1 / n_ref
    ref = np.quantile(counts[1:], 0.8)
    high = np.array(view_rate_scale(space, f, [wide, behind, narrow], 1.0, quantile=0.8)).reshape(9, -1)[:, 0]
    np.testing.assert_allclose(high, np.r_[0.0, np.minimum(counts[1:] / ref, 1.0)], rtol=1e-6)
    assert 1 < ref < 2 and high.min() < 1


def test_the_quantile_is_of_the_observed_bricks():
    """Bricks no camera observes do not pull n_ref to 0: the median of the observed ones decides."""
    f, space = field_over_unit_box(), SceneSpace("world")
    right = -1 + 2 * 11.5 / 15
    narrow = Camera(look_at((right, right, 6.0), (right, right, 0.0)), fov_x=8.0, width=32, height=32)
    wide_half = Camera(look_at((0.0, right, 6.0), (0.0, right, 0.0)), fov_x=30.0, width=32, height=8)  # the +y bricks
    counts = brick_views(space, f, [narrow, wide_half])[1:]
    assert (counts == 0).sum() == 4 and sorted(counts[counts > 0]) == [1, 1, 2, 2]
    scale = np.array(view_rate_scale(space, f, [narrow, wide_half], 1.0, quantile=0.5)).reshape(9, -1)[1:, 0]
    np.testing.assert_allclose(scale, np.minimum(counts / 1.5, 1.0), rtol=1e-6)  # the median of 1, 1, 2, 2


def test_no_camera_observes_nothing():
    f = field_over_unit_box()
    away = Camera(look_at((0.0, 0.0, 6.0), (0.0, 0.0, 12.0)), fov_x=30.0, width=8, height=8)
    assert not np.array(view_rate_scale(SceneSpace("world"), f, [away], 1.0)).any()


def adam_steps(kind=None, factors=None):
    """x after three Adam steps (rate 0.1) from 0 on the gradient G, with ``factors`` set as Adam's
    ``kind`` ('scales' or 'growth') when given."""
    adam = Adam({"x": 0.1})
    if kind is not None:
        getattr(adam, kind)["x"] = mi.Float(factors)
    params = {"x": mi.Float(np.zeros(4, np.float32))}
    for _ in range(3):
        adam.step(params, {"x": mi.Float(G)})
    return np.array(params["x"])


G = np.array([0.3, -2.0, 5.0, -1e-3], np.float32)  # x moves against it: down, up, down, up


def test_adam_scales_its_step_element_by_element():
    """The step of a scaled element is the unscaled one times its factor, whatever the gradient's size."""
    plain = adam_steps()
    np.testing.assert_allclose(adam_steps("scales", [1.0, 0.5, 0.0, 0.25]), plain * [1.0, 0.5, 0.0, 0.25], rtol=1e-6)
    assert np.all(np.abs(plain) > 0.2)  # Adam's sign-like steps: 3 x 0.1, whatever |g|


def test_adam_growth_factors_slow_only_the_steps_that_increase_an_element():
    plain = adam_steps()
    np.testing.assert_allclose(adam_steps("growth", [0.5, 0.5, 0.0, 0.25]), plain * [1.0, 0.5, 1.0, 0.25], rtol=1e-5)
    assert plain[1] > 0 and plain[0] < 0


def test_the_per_brick_rates_stop_at_the_last_stage_only_when_asked():
    """lr_views_final off: the planned schedule's last resolution steps at the phase's rates; the stages
    before it, and the calibration (no plan yet: steps_full None), at the per-brick rates."""
    from types import SimpleNamespace

    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.problem import FieldFit

    def final(resolution, steps_full, lr_views_final):
        cfg = FitConfig().replace(lr_views=1.0, lr_views_final=lr_views_final)
        state = SimpleNamespace(steps_full=steps_full, schedule=[[0, 64], [300, 128], [600, 256]],
                                fields={"full": SimpleNamespace(shape=(resolution, resolution // 2, resolution))})
        return FieldFit.final_stage(SimpleNamespace(inputs=SimpleNamespace(cfg=cfg), state=state), "full")

    assert final(256, 3000, False) and not final(128, 3000, False) and not final(64, None, False)
    assert not final(256, 3000, True)
