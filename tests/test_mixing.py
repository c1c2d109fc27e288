"""Identities and hand-computed cases of the composition rules (paper Eqs. 3 and 5, ablations, density)."""
import mitsuba as mi
import numpy as np
import pytest
from helpers import (
    UNIT_BOX,
    axis_rays,
    box_transform,
    constant_field,
    field_dict,
    integrator,
    numpy_layers,
    random_field,
)

from mi_voldis.render.rays import render_rays
from mi_voldis.transforms import compose

ALL = ("composite", "full", "bg", "fg")


def layers(integ, **kw):
    o, d, u = axis_rays(48, seed=kw.pop("seed", 0))
    return numpy_layers(render_rays(integ, o, d, u, layers=kw.pop("layers", ALL), **kw))


def test_bg_equal_full_gives_zero_foreground():
    integ = integrator(random_field(1), random_field(1), samples=32)
    out = layers(integ)
    for k in range(3):
        assert np.all(out["fg"][k] == 0.0)


def test_empty_background_gives_foreground_equal_full():
    """Background with no density and black colour: w_fg = w_full and c_fg = c_full."""
    empty = field_dict(np.full((2, 2, 2, 1), -100.0), np.full((2, 2, 2, 3), -100.0), UNIT_BOX)
    out = layers(integrator(random_field(2), empty, samples=32))
    for k in range(3):
        np.testing.assert_allclose(out["fg"][k], out["full"][k], atol=1e-6)


@pytest.mark.parametrize("rule", ["c4", "density"])
def test_rules_without_edit_reproduce_full(rule):
    out = layers(integrator(random_field(3), random_field(4), samples=32, composition=rule))
    for k in range(3):
        np.testing.assert_allclose(out["composite"][k], out["full"][k], atol=1e-5)


@pytest.mark.parametrize("rule", ["paper", "c2", "c3"])
def test_paper_rules_do_not_reproduce_full(rule):
    """The paper's rule and c2/c3 differ from the full render when bg and full overlap (why c4 exists)."""
    out = layers(integrator(random_field(3), random_field(4), samples=32, composition=rule))
    assert np.abs(out["composite"][0] - out["full"][0]).max() > 1e-2


def test_paper_composite_is_background_plus_foreground():
    out = layers(integrator(random_field(5), random_field(6), samples=32))
    for k in range(2):
        np.testing.assert_allclose(out["composite"][k], out["bg"][k] + out["fg"][k], atol=1e-6)


@pytest.mark.parametrize("rule", ["paper", "c2", "c3", "c4", "density"])
def test_single_sample_matches_hand_formula(rule):
    """With one sample per ray every weight is an alpha: check each rule against its formula."""
    sf, cf, sb, cb = 0.8, np.array([0.9, 0.2, 0.4]), 0.3, np.array([0.1, 0.6, 0.3])
    integ = integrator(constant_field(sf, cf, UNIT_BOX), constant_field(sb, cb, UNIT_BOX),
                       samples=1, composition=rule)
    rgb = layers(integ, layers=("composite",))["composite"][0]
    af, ab = -np.expm1(-2 * sf), -np.expm1(-2 * sb)
    afg, cfg = af - ab, cf - cb
    expected = {"paper": ab * cb + afg * cfg, "c2": ab * cb + afg * cf, "c3": ab * cb + af * cfg,
                "c4": (ab + afg) * (cb + cfg), "density": af * cf}[rule]
    np.testing.assert_allclose(rgb, np.broadcast_to(expected, rgb.shape), atol=1e-6)


@pytest.mark.parametrize("rule", ["paper", "c4", "density"])
def test_identity_transform_changes_nothing(rule):
    """A foreground transform that is the identity up to rounding (a 360 degree turn) takes the
    transformed code path and must give the untransformed image."""
    full, bg = random_field(7), random_field(8)
    ref = layers(integrator(full, bg, samples=32, composition=rule))
    turn = compose(rotate=("y", 360.0))
    assert not np.array_equal(turn, np.eye(4))
    moved = layers(integrator(full, bg, samples=32, composition=rule,
                              fg_to_world=mi.ScalarTransform4f(turn.astype(np.float32))))
    for layer in ALL:
        np.testing.assert_allclose(moved[layer][0], ref[layer][0], atol=2e-4)


def test_translated_foreground_matches_translated_field():
    """Moving the foreground of (object, empty background) by T renders the object's field moved by T."""
    rng = np.random.default_rng(9)
    density, color = rng.normal(1, 1, (4, 4, 4, 1)), rng.normal(0, 1, (4, 4, 4, 3))
    obj_box = box_transform([-0.5, -0.5, -0.5], [0.2, 0.2, 0.2])
    empty = field_dict(np.full((2, 2, 2, 1), -100.0), np.full((2, 2, 2, 3), -100.0), UNIT_BOX)
    shift = compose(translate=(0.3, 0.2, 0.0))
    moved = layers(integrator(field_dict(density, color, obj_box), empty, samples=64, composition="c4",
                              fg_to_world=mi.ScalarTransform4f(shift.astype(np.float32))))
    direct = layers(integrator(field_dict(density, color, shift @ obj_box), empty, samples=64,
                               mode="full"), layers=("full",))
    np.testing.assert_allclose(moved["composite"][0], direct["full"][0], atol=2e-3)
    np.testing.assert_allclose(moved["fg"][1], direct["full"][1], atol=2e-3)


def test_removal_mode_returns_background():
    from helpers import ortho_scene
    spec = {"type": "voldis", "samples": 16, "mode": "bg", "full": random_field(10), "bg": random_field(11)}
    img = np.array(mi.render(ortho_scene(spec), seed=3))
    names = ortho_scene(spec).integrator().aov_names()
    bg = np.stack([img[..., 3 + names.index(f"bg.{c}")] for c in "RGB"], axis=-1)
    np.testing.assert_array_equal(img[..., :3], bg)


def test_sources_each_rule_needs_are_the_ones_it_reads():
    """needed_sources comes from the rules themselves: the lookup keys compose() reads."""
    from mi_voldis.render.mixing import RULES, Sources, needed_sources
    moved = Sources("full@p", "bg@p", "full@q", "bg@q")
    assert needed_sources("paper", moved, ("full",)) == {"full@p"}
    assert needed_sources("paper", moved, ("bg",)) == {"bg@p"}
    assert needed_sources("paper", moved, ("fg",)) == {"full@q", "bg@q"}
    for rule in RULES:
        assert needed_sources(rule, moved, ("composite",)) == {"bg@p", "full@q", "bg@q"}, rule
    camouflage = Sources("full@p", "bg@p", "full@p", "bg@p", fg_color="cam@q")
    assert needed_sources("c4", camouflage, ("composite",)) == {"bg@p", "full@p", "cam@q"}
    residual = Sources("full@p", "bg@p", "full@p", "bg@p", residual="res@p")
    assert needed_sources("paper", residual, ("full", "res")) == {"full@p", "res@p"}
    with pytest.raises(ValueError, match="unknown composition rule 'c9'"):
        needed_sources("c9", moved, ("composite",))
