"""The full field's edge-aware depth smoothness (``depth_smooth``): its pairs, its values, its gradient and
where the fit applies it."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_voldis.losses import depth_smoothness_loss
from mi_voldis.raybank import tile_pairs, tile_pixels


def pairs_of(tiles, tile):
    p = tile_pairs(tiles, tile)
    return mi.UInt32(p[:, 0]), mi.UInt32(p[:, 1])


@pytest.mark.parametrize("tile", [2, 3, 4])
def test_the_pairs_are_every_adjacent_pixel_pair_of_the_tiles(tile):
    rng = np.random.default_rng(0)
    h, w, tiles = 11, 13, 40
    idx = tile_pixels(rng, rng.integers(0, 2 * h * w, tiles), tile, h, w)
    p = tile_pairs(tiles, tile)
    assert p.dtype == np.uint32 and len(p) == tiles * 2 * tile * (tile - 1)
    a, b = idx[p[:, 0]], idx[p[:, 1]]
    assert (np.abs(b.astype(np.int64) - a) == 1).sum() == tiles * tile * (tile - 1)  # right neighbours
    assert (b.astype(np.int64) - a == w).sum() == tiles * tile * (tile - 1)  # neighbours below
    assert (a // (h * w) == b // (h * w)).all()  # same view
    assert len({tuple(sorted(q)) for q in p.tolist()}) == len(p)  # each pair once


def test_the_smoothness_of_a_two_level_tile_is_the_relative_step_squared():
    # one 2x2 tile: top row at depth 1, bottom row at 3; rows 0.3 apart in colour
    depth, alpha = mi.Float([1, 1, 3, 3]), mi.Float([1, 1, 1, 1])
    flat = mi.Color3f([0.5] * 4, [0.5] * 4, [0.5] * 4)
    assert depth_smoothness_loss(mi.Float([2, 2, 2, 2]), alpha, flat, pairs_of(1, 2))[0] == 0
    # 4 pairs: two along the rows (0), two across them ((1 - 3) / (1 + 3))^2 = 0.25
    np.testing.assert_allclose(depth_smoothness_loss(depth, alpha, flat, pairs_of(1, 2))[0], 0.125, rtol=1e-6)
    edge = mi.Color3f([0.2, 0.2, 0.5, 0.5], [0.2, 0.2, 0.5, 0.5], [0.2, 0.2, 0.5, 0.5])
    np.testing.assert_allclose(depth_smoothness_loss(depth, alpha, edge, pairs_of(1, 2), edge=10.0)[0],
                               0.125 * np.exp(-3.0), rtol=1e-5)
    assert depth_smoothness_loss(depth, alpha, edge, pairs_of(1, 2), edge=0.0)[0] == pytest.approx(0.125)
    # a ray that ends nowhere (alpha 0) takes its pairs out; alpha is clamped to [0, 1]
    np.testing.assert_allclose(depth_smoothness_loss(depth, mi.Float([1, 0, 1, 1]), flat, pairs_of(1, 2))[0],
                               0.25 / 4, rtol=1e-6)
    np.testing.assert_allclose(depth_smoothness_loss(depth, mi.Float([2, 0, 2, 2]), flat, pairs_of(1, 2))[0],
                               0.25 / 4, rtol=1e-6)
    # scale-free: the same scene twice as far costs the same
    np.testing.assert_allclose(depth_smoothness_loss(depth * 2, alpha, flat, pairs_of(1, 2))[0], 0.125,
                               rtol=1e-6)


def test_the_smoothness_gradient_matches_finite_differences_and_leaves_colour_and_alpha_alone():
    rng = np.random.default_rng(3)
    tiles, tile = 3, 3
    n = tiles * tile * tile
    d0 = rng.uniform(0.5, 3.0, n)
    alpha = mi.Float(rng.uniform(0.2, 1.0, n))
    color = mi.Color3f(*(rng.uniform(0, 1, n) for _ in range(3)))
    depth = mi.Float(d0)
    dr.enable_grad(depth, alpha, color)
    loss = depth_smoothness_loss(depth, alpha, color, pairs_of(tiles, tile), edge=2.0)
    dr.backward(loss)
    got = np.array(dr.grad(depth))
    assert not np.array(dr.grad(alpha)).any() and not np.array(dr.grad(color)).any()
    eps = 1e-3
    a_np, c_np = np.array(alpha), np.array(color)
    for i in rng.choice(n, 6, replace=False):
        def value(delta):
            d = d0.copy()
            d[i] += delta
            return depth_smoothness_loss(mi.Float(d), mi.Float(a_np), mi.Color3f(c_np), pairs_of(tiles, tile),
                                         edge=2.0)[0]
        np.testing.assert_allclose(got[i], (value(eps) - value(-eps)) / (2 * eps), rtol=2e-2, atol=1e-6)


def test_the_fit_smooths_the_full_fields_depth_on_tiles_in_its_full_phase_only_and_until_told(
        tiny_dataset, tmp_path, monkeypatch):
    from conftest import TINY_FIT

    from mi_voldis.fit import problem
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.run import run_fit
    calls = []
    real = problem.depth_smoothness_loss

    def record(depth, alpha, color, pairs, edge):
        calls.append((dr.width(depth), dr.width(pairs[0]), edge, dr.grad_enabled(depth)))
        return real(depth, alpha, color, pairs, edge)

    monkeypatch.setattr(problem, "depth_smoothness_loss", record)
    cfg = FitConfig.from_sources(None, TINY_FIT).replace(sh_degree=0)  # no degree trials: the steps are the plan's
    run_fit(tiny_dataset, str(tmp_path / "off"), cfg, progress=False)
    assert not calls  # off by default
    on = cfg.replace(depth_smooth=0.5, depth_smooth_rays=0.5, depth_smooth_tile=3, depth_smooth_edge=4.0)
    run_fit(tiny_dataset, str(tmp_path / "on"), on, progress=False)
    import json
    steps = json.load(open(tmp_path / "on" / "metrics.json"))["schedule"]["steps_full"]
    assert len(calls) == steps  # once a step of the full phase, never in the background's refit
    tiles = int(0.5 * on.batch_rays) // 9
    assert all(c == (tiles * 9, tiles * 12, 4.0, True) for c in calls)
    calls.clear()
    run_fit(tiny_dataset, str(tmp_path / "early"), on.replace(depth_smooth_until=0.4), progress=False)
    assert len(calls) == int(0.4 * steps)  # the full phase's first 40% of planned steps only


def test_in_contracted_space_the_fit_smooths_the_scene_spaces_depth(tiny_dataset, tmp_path, monkeypatch):
    """The depths the smoothness compares are the contracted space's (SceneSpace.scene_depth), bounded by
    the cube's diagonal, where the world depths of the same rays run far past it."""
    from conftest import TINY_FIT

    from mi_voldis.fit import problem
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.run import run_fit
    from mi_voldis.space import SceneSpace
    seen, world = [], []
    real, real_depth = problem.depth_smoothness_loss, SceneSpace.scene_depth

    def record(depth, alpha, color, pairs, edge):
        seen.append(np.array(depth))
        return real(depth, alpha, color, pairs, edge)

    def scene_depth(self, o, d, t):
        world.append((self.kind, np.array(t)))
        return real_depth(self, o, d, t)

    monkeypatch.setattr(problem, "depth_smoothness_loss", record)
    monkeypatch.setattr(SceneSpace, "scene_depth", scene_depth)
    cfg = FitConfig.from_sources(None, TINY_FIT).replace(sh_degree=0, space="contract", contract_radius=0.25,
                                                           depth_smooth=0.5, depth_smooth_until=0.2)
    run_fit(tiny_dataset, str(tmp_path / "run"), cfg, progress=False)
    assert seen and len(seen) == len(world) and all(kind == "contract" for kind, _ in world)
    bound = 2 * np.sqrt(3) * (1 + cfg.contract_shell)
    assert max(s.max() for s in seen) < bound < max(t.max() for _, t in world)


def test_the_smoothness_settings_are_validated():
    from mi_voldis.fit.config import FitConfig
    for bad, why in (({"depth_smooth": -1}, "depth_smooth"), ({"depth_smooth_tile": 1}, "depth_smooth_tile"),
                     ({"depth_smooth_rays": 0}, "depth_smooth_rays"), ({"depth_smooth_until": 0}, "depth_smooth_until"),
                     ({"depth_smooth_until": 1.5}, "depth_smooth_until")):
        with pytest.raises(ValueError, match=why):
            FitConfig.from_sources(None, bad)

