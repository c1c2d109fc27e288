"""The fitting step's fast path: packed grids as parameters, per-channel Adam rates, packed
regularisers, and tiled ray batches."""
from types import SimpleNamespace

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import field_dict

from mi_voldis.field import bricks, grid
from mi_voldis.field import state as field_state
from mi_voldis.field.spec import brick_field_dict
from mi_voldis.fit.config import FitConfig
from mi_voldis.fit.problem import FieldFit
from mi_voldis.optim.adam import Adam
from mi_voldis.optim.parameters import PackedParameters
from mi_voldis.raybank import tile_pixels
from mi_voldis.regularizers import add_tv_gradient, tv_gradient


def random_field(shape=(3, 4, 5), channels=3, seed=0):
    rng = np.random.default_rng(seed)
    d = rng.normal(size=shape + (1,)).astype(np.float32)
    c = rng.normal(size=shape + (channels,)).astype(np.float32)
    return mi.load_dict(field_dict(d, c)), d, c


def test_set_packed_round_trip_and_size_check():
    field, d, c = random_field(channels=12)  # 13 channels: packet width 16
    new_d, new_c = d + 1.0, c * 2.0
    field.set_packed(grid.pack([mi.TensorXf(new_d), mi.TensorXf(new_c)]))
    assert np.array_equal(np.array(field.density), new_d)
    assert np.array_equal(np.array(field.color), new_c)
    sigma, _ = field.eval_local(mi.Point3f(0.0, 0.0, 0.0), mi.Vector3f(0, 0, 1))
    np.testing.assert_allclose(np.array(sigma), [np.logaddexp(0, new_d[0, 0, 0, 0])], rtol=1e-6)
    with pytest.raises(ValueError, match="packed grid needs 960 values, got 959"):
        field.set_packed(dr.zeros(mi.Float, 959))


def test_adam_on_packed_grid_matches_adam_on_tensors():
    """One packed array with per-channel rates steps exactly like the two tensors with their own rates."""
    field, d, c = random_field()
    rng = np.random.default_rng(1)
    g_d, g_c = rng.normal(size=d.shape).astype(np.float32), rng.normal(size=c.shape).astype(np.float32)
    tensors = {"density": mi.TensorXf(d), "color": mi.TensorXf(c)}
    adam_t = Adam({"density": 0.1, "color": 0.05})
    params = PackedParameters({"full": field})
    adam_p = Adam({"full.packed": params.per_slot("full", 0.1, 0.05)})
    for scale in (1.0, 0.5):
        adam_t.step(tensors, {"density": mi.Float(g_d.ravel()), "color": mi.Float(g_c.ravel())}, scale)
        g_packed = grid.pack([mi.TensorXf(g_d), mi.TensorXf(g_c)])
        adam_p.step(params, {"full.packed": g_packed}, scale)
        params.update()
    assert type(params["full.packed"]) is mi.Float  # float32 throughout, never promoted
    np.testing.assert_allclose(np.array(field.density), np.array(tensors["density"]), rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(np.array(field.color), np.array(tensors["color"]), rtol=1e-6, atol=1e-7)
    padding = np.array(field.packed).reshape(-1, field.width)[:, field.channels:]
    assert field.width == 4 and not padding.size  # RGB: no padding; a zero-rate slot is tested below


def test_adam_zero_rate_slots_stay_put():
    x = mi.Float(np.arange(8, dtype=np.float32))
    params = {"x": x}
    Adam({"x": [0.0, 0.5]}).step(params, {"x": dr.full(mi.Float, 1.0, 8)})
    out = np.array(params["x"])
    assert np.array_equal(out[0::2], np.arange(0, 8, 2))
    np.testing.assert_allclose(out[1::2], np.arange(1, 8, 2) - 0.5, rtol=1e-6)


def test_adam_on_a_subset_steps_as_the_whole_array_with_a_masked_gradient():
    """Moments kept for the subset alone, per-slot rates, per-element scales and warm-up: the same values,
    bit for bit, as Adam on the whole array whose gradient is zero off the subset (which never moves)."""
    rng = np.random.default_rng(1)
    n = 40
    x0 = rng.normal(size=n).astype(np.float32)
    subset = np.sort(rng.choice(n, 13, replace=False)).astype(np.uint32)
    scale = rng.uniform(0.5, 2, n).astype(np.float32)
    whole, part = Adam({"x": [0.1, 0.05]}, warmup=3), Adam({"x": [0.1, 0.05]}, warmup=3)
    whole.scales["x"] = part.scales["x"] = mi.Float(scale)
    part.subsets["x"] = mi.UInt32(subset)
    pw, pp = {"x": mi.Float(x0)}, {"x": mi.Float(x0)}
    for _ in range(5):
        g = rng.normal(size=n).astype(np.float32)
        masked = np.zeros(n, np.float32)
        masked[subset] = g[subset]
        whole.step(pw, {"x": mi.Float(masked)})
        part.step(pp, {"x": mi.Float(g[subset])})
    np.testing.assert_array_equal(np.array(pp["x"]), np.array(pw["x"]))
    assert dr.width(part.m["x"]) == len(subset)
    moved = np.array(pp["x"]) != x0
    assert moved[subset].all() and not np.delete(moved, subset).any()
    part.subsets["x"] = mi.UInt32()  # an empty region: nothing moves
    before = np.array(pp["x"])
    part.step(pp, {"x": mi.Float(g)})
    np.testing.assert_array_equal(np.array(pp["x"]), before)


@pytest.mark.parametrize("colors", [3, 12])
def test_tv_gradient_at_some_elements_is_the_whole_gradient_there(colors):
    """The whole array's gradient (in packets of 4 channels) and the one at chosen elements (one by one)
    agree bit for bit, at colour degree 0 (width 4) and 1 (width 16)."""
    rng = np.random.default_rng(2)
    d, c = rng.normal(0, 1, (5, 6, 7, 1)).astype(np.float32), rng.normal(0, 1, (5, 6, 7, colors)).astype(np.float32)
    field = mi.load_dict(brick_field_dict(d, c, brick=4))
    state = field_state.FieldState(field.layout, field.packed, 1 + colors, np.eye(4))
    neighbours = field_state.neighbour_vertices(state)
    at = np.sort(rng.choice(dr.width(field.packed), 500, replace=False)).astype(np.uint32)
    whole = np.array(tv_gradient(field.packed, field.width, neighbours))
    np.testing.assert_array_equal(np.array(tv_gradient(field.packed, field.width, neighbours, mi.UInt32(at))),
                                  whole[at])


@pytest.mark.parametrize("colors", [3, 12])
def test_tv_added_in_packets_is_the_weighted_gradient_added(colors):
    """``add_tv_gradient`` adds weight[channel] times the TV gradient to what it is given."""
    rng = np.random.default_rng(4)
    d, c = rng.normal(0, 1, (5, 6, 7, 1)).astype(np.float32), rng.normal(0, 1, (5, 6, 7, colors)).astype(np.float32)
    field = mi.load_dict(brick_field_dict(d, c, brick=4))
    state = field_state.FieldState(field.layout, field.packed, 1 + colors, np.eye(4))
    neighbours = field_state.neighbour_vertices(state)
    n, width = dr.width(field.packed), field.width
    weights = list(rng.uniform(0.5, 2.0, width))
    base = rng.normal(size=n).astype(np.float32)
    got = np.array(add_tv_gradient(mi.Float(base), field.packed, width, neighbours, weights))
    want = base + np.tile(weights, n // width) * np.array(tv_gradient(field.packed, width, neighbours))
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-7)


def test_packed_regularisers_match_the_tensor_formulas():
    """On a brick grid with every brick allocated: sparsity on density, TV on every channel group with its
    own weight (the dense formula on each tensor), the hull mask and the density's own mask within it,
    padding and the empty brick untouched. The TV weights are the phase's own (the background refit has
    its own), not the config's. Within a hull the gradient comes at the hull's elements alone (Adam's
    subset): scattered back, it is the masked dense one."""
    rng = np.random.default_rng(3)
    d, c = rng.normal(0, 1, (5, 6, 7, 1)).astype(np.float32), rng.normal(0, 1, (5, 6, 7, 12)).astype(np.float32)
    field = mi.load_dict(brick_field_dict(d, c, brick=4))
    layout, b3 = field.layout, field.layout.vertices_per_brick
    cfg = FitConfig(tv_every=2, tv_density=5.0, tv_color=7.0, sparsity=1e-1)
    tv_density, tv_color = 1e-2, 3e-3
    params = PackedParameters({"full": field})
    coords, inside = layout.vertex_coords()
    keep = (np.arange(field.layout.slots * b3) % 3 != 0).astype(np.float32)
    shaped = (np.arange(field.layout.slots * b3) % 2 != 0).astype(np.float32)
    state = field_state.FieldState(layout, field.packed, 13, np.eye(4))
    fake = SimpleNamespace(inputs=SimpleNamespace(cfg=cfg), roles=("full",), params=params, hull=mi.Float(keep),
                           tv=(tv_density, tv_color),
                           density_hull=mi.Float(shaped),
                           integrator=SimpleNamespace(fields={"full": field}), neighbours={},
                           state=SimpleNamespace(fields={"full": state}), adam=Adam({}), view_onset=lambda: 0)
    subset = FieldFit.refit_elements(fake, field)
    vertices = np.flatnonzero(keep[b3:]) + b3  # the hull's, the empty brick left out
    # density and the mean colour: a refit leaves the view-dependent coefficients as they are
    np.testing.assert_array_equal(np.array(subset), (vertices[:, None] * 16 + np.arange(4)).ravel())
    fake.adam.subsets["full.packed"] = subset
    grads = FieldFit.extra_gradients(fake, 4, {"full.packed": dr.zeros(mi.Float, dr.width(field.packed))})
    assert dr.width(grads["full.packed"]) == dr.width(subset)
    whole = dr.zeros(mi.Float, dr.width(field.packed))
    dr.scatter(whole, grads["full.packed"], subset)
    grads["full.packed"] = whole
    got = bricks.to_dense(np.array(grads["full.packed"]), layout, 16)
    stored = layout.slots * b3  # the means are over stored vertices (the empty brick and padding too)
    td, tc = d[..., 0], c

    def dense_tv(t):  # gradient of sum_v sum_axis (t[v+e] - t[v])^2, Neumann border, per channel
        g = np.zeros_like(t)
        for axis in range(3):
            diff = np.diff(t, axis=axis)
            pad = [(0, 0)] * t.ndim
            pad[axis] = (1, 0)
            g += 2 * np.pad(diff, pad)  # d/dt[v] of (t[v] - t[v-1])^2
            pad[axis] = (0, 1)
            g -= 2 * np.pad(diff, pad)  # d/dt[v] of (t[v+1] - t[v])^2
        return g
    want_d = (cfg.sparsity / stored) / (1 + np.exp(-td)) + 2 * tv_density * 16 * dense_tv(td) / (stored * 16)
    want_c = 2 * tv_color * 16 / 12 * dense_tv(tc) / (stored * 16)
    mask = bricks.to_dense(np.repeat(keep, 16), layout, 16)[..., 0]
    density_mask = mask * bricks.to_dense(np.repeat(shaped, 16), layout, 16)[..., 0]
    assert 0 < density_mask.sum() < mask.sum()
    np.testing.assert_allclose(got[..., 0], want_d * density_mask, rtol=1e-4, atol=1e-8)
    np.testing.assert_allclose(got[..., 1:4], want_c[..., :3] * mask[..., None], rtol=1e-4, atol=1e-8)
    packed = np.array(grads["full.packed"]).reshape(-1, 16)
    assert not packed[:, 4:].any() and not packed[:b3].any()  # view dependence, padding, the empty brick
    # without a hull: every element, the whole array's gradient
    fake.hull = fake.density_hull = None
    fake.adam.subsets.clear()
    grads = FieldFit.extra_gradients(fake, 4, {"full.packed": dr.zeros(mi.Float, dr.width(field.packed))})
    got = bricks.to_dense(np.array(grads["full.packed"]), layout, 16)
    np.testing.assert_allclose(got[..., 0], want_d, rtol=1e-4, atol=1e-8)
    np.testing.assert_allclose(got[..., 1:13], want_c, rtol=1e-4, atol=1e-8)
    packed = np.array(grads["full.packed"]).reshape(-1, 16)
    assert not packed[:, 13:].any() and not packed[:b3].any()


@pytest.mark.parametrize("kind", ["8-bit", "10-bit", "10-bit, no masks", "float", "float, no masks"])
def test_a_batch_holds_the_datasets_pixels_packed_or_not(tiny_dataset, kind):
    """8-bit photographs are kept as one UInt32 a pixel (codes and mask bit) and a batch gives their values
    bit for bit; other images in [0, 1] as 10-bit codes, within half a 10-bit step; images with a value
    outside [0, 1] as floats (and no mask array where the dataset has no masks), bit for bit. Masks exact."""
    from mi_voldis.data import load_dataset
    from mi_voldis.raybank import RayBank
    ds = load_dataset(tiny_dataset)
    masks = ds.masks.copy()
    assert masks.any()
    if kind != "8-bit":
        ds.images = ds.images.copy()
        # one value off the 8-bit levels (10 bits for the whole bank), or above 1 (floats for it)
        ds.images[ds.train[-1], 3, 5, 1] = 0.3 if kind.startswith("10-bit") else 1.25
        ds.images[ds.train[0], 2, 2] = [0.5, 0.0, 1.0]  # 1023 / 2 rounds half to even, and both ends
    if kind.endswith("no masks"):
        ds.masks, masks = None, np.zeros_like(masks)
    bank = RayBank(ds, ds.train)
    assert bank.bits == {"8-bit": 8, "10-bit": 10, "10-bit, no masks": 10}.get(kind)
    assert (kind == "float, no masks") == (bank.codes is None and bank.masks is None)
    index = np.random.default_rng(0).integers(0, bank.pixels, 500).astype(np.uint32)
    index[0] = (len(ds.train) - 1) * bank.height * bank.width + 3 * bank.width + 5  # the changed pixels
    index[1] = 2 * bank.width + 2
    _, _, color, mask, _ = bank.rays(index, np.full((500, 2), 0.5, np.float32))
    view, pixel = np.divmod(index, bank.height * bank.width)
    photos = ds.images[ds.train].reshape(len(ds.train), -1, 3)
    if kind.startswith("10-bit"):
        got = np.array(color).T
        np.testing.assert_allclose(got, photos[view, pixel], rtol=0, atol=0.5 / 1023 + 1e-7)
        np.testing.assert_array_equal(got * 1023, np.rint(got * 1023))  # on the 10-bit levels
        np.testing.assert_array_equal(got[1], [np.float32(512) / np.float32(1023), 0.0, 1.0])  # 511.5 -> 512
    else:
        np.testing.assert_array_equal(np.array(color).T, photos[view, pixel])
    np.testing.assert_array_equal(np.array(mask), masks[ds.train].reshape(len(ds.train), -1)[view, pixel])


def test_images_are_packed_at_8_bits_on_its_levels_else_10_within_0_1_else_not_and_raise_no_warning():
    """Values between two 8-bit levels: 10 bits; above 1, below 0 or NaN (images a caller made, not read
    from files): floats."""
    import warnings

    from mi_voldis.raybank import EIGHT_BIT_LEVELS, packed_pixels
    masks = np.zeros((1, 2, 2), bool)
    masks[0, 1, 1] = True
    base = np.broadcast_to(EIGHT_BIT_LEVELS[[0, 7, 200, 255]].reshape(1, 2, 2, 1), (1, 2, 2, 3)).copy()
    codes, bits = packed_pixels(base, [0], masks)
    assert bits == 8 and codes[0, 1, 1] == 255 * 0x010101 + (1 << 24) and codes[0, 0, 1] == 7 * 0x010101
    for bad, want in ((0.5, 10), (1.5, None), (-0.25, None), (np.nan, None)):
        images = base.copy()
        images[0, 1, 0, 2] = bad
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            packed = packed_pixels(images, [0], masks)
        assert (None if packed is None else packed[1]) == want
    codes, bits = packed_pixels(np.full((1, 2, 2, 3), 0.5, np.float32), [0], masks)
    assert bits == 10 and codes[0, 1, 1] == 512 | (512 << 10) | (512 << 20) | (1 << 30)


def test_tiles_cover_their_anchor_inside_the_image():
    rng = np.random.default_rng(0)
    h, w, t = 7, 9, 4
    anchors = rng.integers(0, 3 * h * w, 500)
    idx = tile_pixels(rng, anchors, t, h, w).reshape(-1, t * t)
    view, pix = np.divmod(idx, h * w)
    y, x = np.divmod(pix, w)
    assert (view == (anchors // (h * w))[:, None]).all()
    assert (idx == anchors[:, None]).any(axis=1).all()
    assert ((y >= 0) & (y < h) & (x >= 0) & (x < w)).all()
    assert all(len(set(row)) == t * t for row in idx)
    # row-major t x t blocks of adjacent pixels
    assert (np.diff(x.reshape(-1, t, t), axis=2) == 1).all() and (np.diff(y.reshape(-1, t, t), axis=1) == 1).all()


def test_bench_rays_are_reproducible_and_tiles_are_coherent():
    from mi_voldis.bench.rays import TILE, bench_rays
    for kind in ("random", "tiles"):
        o, d, u = bench_rays(kind, 4096, 3)
        assert all(a.dtype == np.float32 for a in (o, d, u))
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, rtol=1e-6)
        np.testing.assert_allclose(np.linalg.norm(o, axis=1), 3.0, rtol=1e-6)
        assert np.array_equal(o, bench_rays(kind, 4096, 3)[0]) and not np.array_equal(d, bench_rays(kind, 4096, 4)[1])
        # the closest point of every ray to the centre lies inside the box [-1, 1]^3 for most rays
        closest = o - np.sum(o * d, axis=1, keepdims=True) * d
        assert np.mean(np.abs(closest).max(axis=1) < 1.0) > (0.999 if kind == "random" else 0.5)
    o, d, _ = bench_rays("tiles", 4096, 3)
    tiles = d.reshape(-1, TILE * TILE, 3)
    assert (o.reshape(-1, TILE * TILE, 3) == o[::TILE * TILE, None]).all()  # one camera per tile
    spread = np.degrees(np.arccos(np.clip(np.sum(tiles * tiles[:, :1], axis=2), -1, 1))).max()
    assert spread < 1.0  # a tile spans a few pixels of a 45-degree, 256-pixel view


def test_after_every_step_the_fit_state_holds_the_values_adam_made(tiny_dataset, tmp_path, monkeypatch):
    """The state's fields are the arrays the march reads after each step, not the values of the last
    occupancy update (a stale copy would hold a grid's worth of memory at the step's peak)."""
    from conftest import TINY_FIT

    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.run import run_fit
    seen = []
    after = FieldFit.after_step

    def check(self, step):
        after(self, step)
        for r in self.roles:
            seen.append((self.state.fields[r].data is self.integrator.fields[r].packed,
                         np.array_equal(np.array(self.state.fields[r].data),
                                        np.array(self.params[f"{r}.packed"]))))

    monkeypatch.setattr(FieldFit, "after_step", check)
    run_fit(tiny_dataset, str(tmp_path / "run"), FitConfig.from_sources(None, TINY_FIT), progress=False)
    assert len(seen) > 60  # every step of both phases
    assert all(same and equal for same, equal in seen)


def test_adam_holds_write_their_value_after_every_step_and_leave_the_rest_as_without():
    """Held elements equal their value after each step, whatever their gradient; every other element and the
    moments are those of the same steps without the hold, bit for bit."""
    rng = np.random.default_rng(3)
    n = 30
    x0 = rng.normal(size=n).astype(np.float32)
    held = np.array([2, 7, 8, 29], np.uint32)
    free, hold = Adam({"x": 0.1}), Adam({"x": 0.1})
    hold.holds["x"] = (mi.UInt32(held), -20.0)
    pf, ph = {"x": mi.Float(x0)}, {"x": mi.Float(x0)}
    other = ph["x"]  # a second reference to the first array: the hold must not write into it
    for _ in range(4):
        g = mi.Float(rng.normal(size=n).astype(np.float32))
        free.step(pf, {"x": g})
        hold.step(ph, {"x": g})
        out = np.array(ph["x"])
        assert np.all(out[held] == -20.0)
        np.testing.assert_array_equal(np.delete(out, held), np.delete(np.array(pf["x"]), held))
    np.testing.assert_array_equal(np.array(hold.m["x"]), np.array(free.m["x"]))
    np.testing.assert_array_equal(np.array(other), x0)
