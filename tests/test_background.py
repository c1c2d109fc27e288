"""The background prior and its pieces: disparity fill, visibility, the lifted surface, residue-free removal."""
import dataclasses

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import mi_voldis  # noqa: F401
from mi_voldis.cameras import Camera, pixel_of, pixel_rays, project
from mi_voldis.data.types import Dataset
from mi_voldis.device import from_numpy
from mi_voldis.field.state import new_field, vertex_positions
from mi_voldis.fit.config import FitConfig
from mi_voldis.fit.lift import lift_pixels, write_surface
from mi_voldis.fit.visibility import hidden_depth, hidden_surface_side, seen_elsewhere
from mi_voldis.inpaint2d import INPAINTERS, fill_disparity, harmonic_fill, has_contrib, inpainter, resolve
from mi_voldis.metrics import dilate, object_residue
from mi_voldis.render.views import render_camera
from mi_voldis.scene import build_integrator, integrator_properties
from mi_voldis.space import SceneBox, SceneSpace
from mi_voldis.synth.rigs import look_at, orbit

FLOOR_Y = -0.5


def plane_depth(camera, y=FLOOR_Y):
    """Distance along each pixel-centre ray to the plane y = ``y`` (inf where the ray misses it)."""
    py, px = np.mgrid[0:camera.height, 0:camera.width]
    o, d = pixel_rays(camera, px.ravel() + 0.5, py.ravel() + 0.5)
    with np.errstate(divide="ignore"):
        t = (y - o[:, 1]) / d[:, 1]
    return np.where(t > 0, t, np.inf).reshape(camera.height, camera.width)


def sphere_hit(o, d, centre, radius):
    """Distance to the first hit of unit rays (o, d) with a sphere (inf where they miss)."""
    oc = o - centre
    b = np.sum(oc * d, axis=-1)
    disc = b * b - (np.sum(oc * oc, axis=-1) - radius ** 2)
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    return np.where((disc > 0) & (t > 0), t, np.inf)


def test_fill_disparity_continues_a_plane_exactly():
    cam = Camera(look_at([0.3, 1.0, 2.5], [0.0, FLOOR_Y, 0.0]), 50.0, 64, 48)
    depth = plane_depth(cam)
    assert np.isfinite(depth).all()
    hole = np.zeros(depth.shape, bool)
    hole[14:34, 20:44] = True
    corrupted = np.where(hole, 1e3, depth)
    corrupted[13, 25:29] *= 0.5  # an occluder's edge on the ring: trimmed from the plane fit
    filled = fill_disparity(corrupted, hole, camera=cam)
    np.testing.assert_allclose(filled[hole], depth[hole], rtol=1e-3)


def test_harmonic_fill_reproduces_affine_data_and_stays_within_its_boundary():
    y, x = np.mgrid[0:40, 0:50].astype(np.float64)
    affine = 0.3 + 0.02 * x - 0.01 * y
    hole = np.zeros(affine.shape, bool)
    hole[5:35, 8:45] = True
    np.testing.assert_allclose(harmonic_fill(affine, hole)[hole], affine[hole], atol=1e-3)
    rng = np.random.default_rng(0)
    noisy = rng.uniform(-1, 1, affine.shape)
    out = harmonic_fill(noisy, hole)
    ring = dilate(hole, 1) & ~hole
    assert out[hole].max() <= noisy[ring].max() + 1e-9 and out[hole].min() >= noisy[ring].min() - 1e-9


def test_the_volumetric_harmonic_fill_of_an_empty_region_changes_nothing():
    """A hull no vertex of the grid lies in (a grid kept coarse): the fill returns the values as they are."""
    from mi_voldis.field.state import neighbour_vertices
    from mi_voldis.fit.background import harmonic_fill as fill3d
    field = new_field(np.zeros(3), np.ones(3), 8, 0, -3.0, 1.0, 4)
    values = field.data + dr.arange(mi.Float, dr.width(field.data))
    out = fill3d(values, field.width, dr.zeros(mi.Float, field.vertices), neighbour_vertices(field))
    np.testing.assert_array_equal(np.array(out), np.array(values))


def test_the_world_up_is_orthogonal_to_level_cameras_x_axes_and_a_forward_rigs_own_up_otherwise():
    from mi_voldis.cameras import world_up
    angle = 0.7  # the world turned about an arbitrary axis: up goes with it
    axis = np.array([1.0, 2.0, 0.5]) / np.linalg.norm([1.0, 2.0, 0.5])
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    turn = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k
    cams = orbit(12, [0.0, 0.2, 0.0], 3.0, [20.0, 50.0], 40.0, 8, 8)  # pitched 20-50 degrees down
    for c in cams:
        c.to_world = c.to_world.copy()
        c.to_world[:3, :] = turn @ c.to_world[:3, :]
    np.testing.assert_allclose(world_up(cams), turn @ [0.0, 1.0, 0.0], atol=1e-9)
    # a forward rig: every camera alike, so its +x axes cannot tell up from forward; up is its own +y
    frame = look_at([0.0, 1.0, 3.0], [0.0, 0.0, 0.0])
    forward = [Camera(frame.copy(), 50.0, 8, 8) for _ in range(5)]
    np.testing.assert_allclose(world_up(forward), frame[:3, 1], atol=1e-9)


def test_a_fill_along_the_horizontal_continues_a_floor_and_leaves_the_air_above_it_empty():
    """A floor (raw density 5) at the lowest 3 vertex layers of a field whose other vertices are air
    (-5), a region through both from the floor's bottom up: filled with the vertical weight 0, every
    horizontal slice takes its rim's value, so the floor and the air come back exactly; the isotropic fill
    carries the floor's density upwards into the region's air."""
    from mi_voldis.field.state import neighbour_vertices
    from mi_voldis.fit.background import harmonic_fill as fill3d
    field = new_field(np.zeros(3), np.ones(3), 16, 0, -5.0, 1.0, 4)
    pts, _ = vertex_positions(field)
    y = np.rint(pts[:, 1] * 15).astype(int)
    floor = np.where(y <= 2, 5.0, -5.0)
    values = from_numpy(mi.Float, np.repeat(floor, field.width).astype(np.float32))
    ijk = np.rint(pts * 15).astype(int)
    inner = np.all((ijk[:, [0, 2]] >= 4) & (ijk[:, [0, 2]] <= 11), 1) & (y >= 1) & (y <= 11)
    region = from_numpy(mi.Float, inner.astype(np.float32))
    nb = neighbour_vertices(field)
    flat = np.array(fill3d(values, field.width, region, nb, iterations=600,
                           weights=[1.0, 1.0, 0.0, 0.0, 1.0, 1.0]))[::field.width]
    np.testing.assert_allclose(flat, floor, atol=1e-3)
    iso = np.array(fill3d(values, field.width, region, nb, iterations=600))[::field.width]
    above = inner & (y == 3)  # air a vertex above the floor
    assert iso[above].min() > -3.0 and iso[inner & (y == 6)].max() > -4.5


def test_a_ceiling_in_the_fill_solves_the_obstacle_problem_exactly_and_changes_nothing_when_loose():
    """The fill along x alone (weights 0 on y and z: every x line its own 1D problem) of the vertices
    1..14 of each line, the ends at raw density 1. Without a ceiling the line is 1 throughout; with the
    density capped at -2 on the middle vertex (x = 7: a veil views see through), the 1D obstacle problem's
    solution is the two straight lines from the ends down to -2 there, and the colour channel, under no
    ceiling, stays 1. A ceiling above every value gives the plain fill bit for bit."""
    from mi_voldis.field.state import neighbour_vertices
    from mi_voldis.fit.background import density_ceiling
    from mi_voldis.fit.background import harmonic_fill as fill3d
    field = new_field(np.zeros(3), np.ones(3), 16, 0, 1.0, 1.0, 4)
    pts, real = vertex_positions(field)
    i = np.rint(pts[:, 0] * 15).astype(int)
    values = from_numpy(mi.Float, np.ones(field.vertices * field.width, np.float32))
    region = from_numpy(mi.Float, ((i >= 1) & (i <= 14) & real).astype(np.float32))
    along_x, nb = [1.0, 1.0, 0.0, 0.0, 0.0, 0.0], neighbour_vertices(field)
    veil = from_numpy(mi.Bool, (i == 7) & real)
    capped = dr.select(dr.arange(mi.UInt32, dr.width(values)) % field.width == 0, values - 3.0, values)
    out = np.array(fill3d(values, field.width, region, nb, iterations=3000, weights=along_x,
                          ceiling=density_ceiling(capped, field.width, veil))).reshape(-1, field.width)
    obstacle = np.where(i <= 7, 1.0 - 3.0 * i / 7, -2.0 + 3.0 * (i - 7) / 8)
    np.testing.assert_allclose(out[real, 0], obstacle[real], atol=1e-4)
    np.testing.assert_allclose(out[real, 1:], 1.0, atol=1e-4)
    plain = fill3d(values, field.width, region, nb, weights=along_x)
    loose = fill3d(values, field.width, region, nb, weights=along_x,
                   ceiling=density_ceiling(values + 1.0, field.width, veil))
    np.testing.assert_array_equal(np.array(loose), np.array(plain))


def test_the_filled_colour_comes_from_around_the_hull_not_from_the_vertices_views_see_in_it():
    """hull_fill: a hull (a box of vertices) in a field of one colour c and density s, and in it a slab of
    vertices views see (kept: their own density, and the object's tint as colour). The density fill takes
    the kept density in as its boundary; the colour fill's boundary is the colour around the hull alone, so
    every filled vertex takes c (the harmonic extension of a constant); the kept vertices keep their own
    values. Filled as the density is (harmonic_fill), the colour carries the tint beside the slab."""
    from mi_voldis.field.state import neighbour_vertices
    from mi_voldis.fit.background import harmonic_fill as fill3d
    from mi_voldis.fit.background import hull_fill
    field = new_field(np.zeros(3), np.ones(3), 12, 0, -3.0, 1.0, 4)
    pts, real = vertex_positions(field)
    w = field.width
    hull = real & np.all((pts > 0.25) & (pts < 0.75), axis=1)
    kept = hull & (pts[:, 0] > 0.4) & (pts[:, 0] < 0.5)
    inner = hull & ~kept
    assert kept.any() and inner.sum() > kept.sum()
    values = np.array(field.data).reshape(-1, w)
    values[:, 0], values[:, 1:] = 1.0, 0.3  # s, c
    values[kept, 0], values[kept, 1:] = 5.0, 2.0  # what views see in the hull: its density, the object's tint
    values[inner, :] = np.random.default_rng(0).uniform(-4, 4, (inner.sum(), w))  # to be filled
    packed = mi.Float(values.ravel())
    neighbours = neighbour_vertices(field)
    region = mi.Float(inner.astype(np.float32))
    out = np.array(hull_fill(packed, w, region, mi.Float(hull.astype(np.float32)), neighbours)).reshape(-1, w)
    np.testing.assert_array_equal(out[~inner], values[~inner])  # the kept vertices and the rest stay
    np.testing.assert_allclose(out[inner, 1:], 0.3, atol=1e-4)  # the filled colour: c
    assert (out[inner, 0] > 1.0).all() and (out[inner, 0] < 5.0).all()  # the density between s and the kept's
    beside = inner & (np.abs(pts[:, 0] - 0.45) < 0.15)
    assert out[beside, 0].min() > 1.5  # ... which it takes in
    old = np.array(fill3d(packed, w, region, neighbours)).reshape(-1, w)  # every channel from all around
    np.testing.assert_array_equal(old[:, 0], out[:, 0])
    assert old[beside, 1:].min() > 0.3 + 0.2


def test_hull_color_fill_changes_the_starting_backgrounds_colour_alone(tmp_path):
    """The setting reaches the background's start: before any refit step, the background with
    ``hull_color_fill`` has the default's density everywhere and differs in colour only, where it
    fills."""
    from mi_voldis.field.state import density_of
    starts = {}
    for on in (False, True):
        _, _, _, state = guided_removal(tmp_path / str(on), steps_bg=0, hull_color_fill=on)
        bg = state.fields["bg"]
        starts[on] = (np.array(density_of(bg)), np.array(bg.data).reshape(-1, bg.width)[:, 1:bg.channels])
    np.testing.assert_array_equal(starts[True][0], starts[False][0])
    changed = np.any(starts[True][1] != starts[False][1], axis=1)
    assert 0 < changed.sum() < 0.5 * len(changed)


def test_inpainters_are_named_or_callable():
    image = np.random.default_rng(1).uniform(0, 1, (20, 24, 3)).astype(np.float32)
    hole = np.zeros((20, 24), bool)
    hole[6:12, 8:16] = True
    for name in INPAINTERS:
        if name == "fsr" and not has_contrib():  # its refusal there: the test below
            continue
        out = inpainter(name)(image, hole)
        assert out.shape == image.shape and np.isfinite(out).all()
        np.testing.assert_allclose(out[~hole], image[~hole], atol=1 / 255 + 1e-6)
    mine = inpainter(lambda im, h: np.zeros_like(im))
    assert mine(image, hole).sum() == 0
    with pytest.raises(ValueError, match="unknown inpainter 'lama'"):
        inpainter("lama")


def test_the_lateral_fill_is_exact_on_colours_affine_along_the_rows():
    """Colours affine in x (any per-row offset): each row's run is the straight line through the means of
    the pixels beside it, placed at their mean columns, so the fill is exact; with a colour affine in y
    too, rows whose smoothing window lies in the hole are exact as well; the known pixels stay."""
    from mi_voldis.inpaint2d import lateral_inpaint
    h, w = 30, 40
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    hole = np.zeros((h, w), bool)
    hole[8:22, 12:27] = True
    hole[10:14, 27:30] = True  # a ragged edge: the runs differ in length
    rows = np.random.default_rng(2).uniform(0, 0.5, h)[:, None]
    image = np.stack([0.1 + 0.02 * x + rows, 0.9 - 0.015 * x + 0 * rows, 0.3 + 0.01 * x + rows], -1)
    out = lateral_inpaint(image.astype(np.float32), hole, smooth=0)
    np.testing.assert_allclose(out[hole], image[hole], atol=1e-5)
    np.testing.assert_array_equal(out[~hole], image.astype(np.float32)[~hole])
    affine = np.stack([0.1 + 0.01 * x + 0.02 * y, 0.5 - 0.01 * y, 0.2 + 0.005 * x], -1).astype(np.float32)
    out = lateral_inpaint(affine, hole, smooth=2)
    inner = hole & np.roll(hole, 2, 0) & np.roll(hole, -2, 0)
    assert inner.sum() > 100
    np.testing.assert_allclose(out[inner], affine[inner], atol=1e-5)


def test_the_lateral_fill_continues_the_bands_beside_a_tall_hole_where_telea_carries_the_pedestal_up():
    """A statue on a white pedestal before horizontal bands (lawn, path, hedge): the lateral fill gives each
    band's own colour across the hole, the pedestal's white goes no higher than the pedestal; Telea fills
    from every side and carries the white upward."""
    from mi_voldis.inpaint2d import lateral_inpaint
    h, w = 60, 40
    bands = np.array([[0.1, 0.3, 0.1], [0.5, 0.5, 0.5], [0.2, 0.6, 0.2]])  # hedge, path, lawn (top to bottom)
    image = np.repeat(bands, 20, 0)[:, None, :].repeat(w, 1).astype(np.float32)
    image[50:, 10:30] = 0.95  # the pedestal
    hole = np.zeros((h, w), bool)
    hole[5:50, 14:26] = True  # the statue, standing on the pedestal
    row = np.arange(h)[:, None]
    away = hole & (np.minimum(np.abs(row - 20), np.abs(row - 40)) > 2)  # off the band edges (smooth = 2)
    lateral, telea = lateral_inpaint(image, hole), inpainter("telea")(image, hole)
    np.testing.assert_allclose(lateral[away], image[away], atol=1e-6)
    lowest = hole & (row >= 44)  # the lawn just over the pedestal
    assert np.abs(lateral[lowest] - image[lowest]).max() < 1e-6
    assert np.abs(telea[lowest] - image[lowest]).mean() > 0.1


def test_the_lateral_fill_takes_the_one_side_it_has_and_fills_whole_rows_from_above_and_below():
    """A hole at the image's left edge takes its right side's colour; rows that are hole from edge to edge
    have nothing beside them and take the harmonic fill between the rows above and below."""
    from mi_voldis.inpaint2d import lateral_inpaint
    image = np.zeros((20, 16, 3), np.float32)
    image[:, :, 0] = np.linspace(0, 1, 16)[None, :]
    image[:10, :, 1], image[10:, :, 1] = 0.2, 0.8
    hole = np.zeros((20, 16), bool)
    hole[2:6, :5] = True
    hole[9:11, :] = True
    out = lateral_inpaint(image, hole, band=3, smooth=0)
    np.testing.assert_allclose(out[2:6, :5, 0], image[2, 5:8, 0].mean(), atol=1e-6)
    whole = out[9:11, :, 1]
    assert np.isfinite(out).all() and (whole > 0.2).all() and (whole < 0.8).all()
    assert whole[0].mean() < whole[1].mean()  # nearer the row above, nearer its colour


needs_contrib = pytest.mark.skipif(not has_contrib(), reason="needs OpenCV's contrib modules (cv2.xphoto): "
                                                               "opencv-contrib-python-headless is not installed")


@needs_contrib
def test_fsr_continues_stripes_that_telea_smears():
    """Vertical stripes (period 8 px) with a 12 x 12 hole: OpenCV contrib's frequency-selective
    reconstruction carries the stripes through (under a third of Telea's error there), the known pixels
    stay as they were."""
    x = np.arange(48)
    stripes = np.where((x // 4) % 2 == 0, 0.8, 0.2)
    image = np.repeat(np.broadcast_to(stripes, (40, 48))[..., None], 3, -1).astype(np.float32)
    hole = np.zeros((40, 48), bool)
    hole[14:26, 18:30] = True
    fsr, telea = inpainter("fsr")(image, hole), inpainter("telea")(image, hole)
    error = {name: np.abs(out[hole] - image[hole]).mean() for name, out in (("fsr", fsr), ("telea", telea))}
    assert error["fsr"] < error["telea"] / 3, error
    np.testing.assert_allclose(fsr[~hole], image[~hole], atol=1 / 255 + 1e-6)


def test_fsr_without_the_contrib_modules_says_what_to_install(monkeypatch):
    import cv2
    monkeypatch.delattr(cv2, "xphoto", raising=False)  # an OpenCV without them already lacks it
    with pytest.raises(RuntimeError, match="opencv-contrib-python-headless"):
        inpainter("fsr")(np.zeros((8, 8, 3), np.float32), np.ones((8, 8), bool))


@needs_contrib
def test_auto_is_fsr_with_the_contrib_modules():
    assert resolve("auto") == "fsr" and inpainter("auto") is INPAINTERS["fsr"]


def test_auto_without_the_contrib_modules_is_telea(monkeypatch):
    """'auto' on an OpenCV without cv2.xphoto (opencv-python, nerfstudio's) is Telea, and says so in a
    line that names the package to install; an explicit 'fsr' still fails."""
    import cv2

    from mi_voldis.inpaint2d import fallback_note
    monkeypatch.delattr(cv2, "xphoto", raising=False)
    assert not has_contrib() and resolve("auto") == "telea" and inpainter("auto") is INPAINTERS["telea"]
    assert "opencv-contrib-python-headless" in fallback_note("auto") and "\n" not in fallback_note("auto")
    assert fallback_note("telea") is None
    with pytest.raises(RuntimeError, match="opencv-contrib-python-headless"):
        inpainter("fsr")(np.zeros((8, 8, 3), np.float32), np.ones((8, 8), bool))


def test_a_fit_without_the_contrib_modules_uses_telea_and_records_it(monkeypatch, tmp_path, capsys):
    """The default prior ('auto') on an OpenCV without cv2.xphoto: the guided refit runs with Telea, one
    note on stderr says so, and the state's prior (metrics.json's bg_prior) records it."""
    import cv2

    from mi_voldis.fit.train import fit
    ds, cfg, full, FitInputs, FitState, Adam = synthetic_object_scene(views=5)
    monkeypatch.delattr(cv2, "xphoto", raising=False)
    cfg = cfg.replace(bg_strategy="guided", steps_bg=2, prior_inpainter="auto")
    state = FitState(np.array([-1.0] * 3), np.array([1.0] * 3), Adam({}, cfg.adam_beta1, cfg.adam_beta2),
                     fields={"full": full})
    state.schedule, state.steps_full = [[0, 40]], 1
    checkpoint = str(tmp_path / "state.npz")
    state.save(checkpoint, "bg", 0)
    _, state = fit(ds, checkpoint, cfg, resume=True, progress=True)
    notes = [line for line in capsys.readouterr().err.splitlines() if "cv2.xphoto" in line]
    assert len(notes) == 1 and notes[0].startswith("note: ") and "'telea'" in notes[0]
    assert state.prior["inpainter"] == "telea"


def test_the_background_refit_steps_with_its_own_rates_and_tv(monkeypatch, tmp_path):
    """The refit takes bg_lr_* and bg_tv_*, not the full phase's lr_* and tv_*: its Adam rates per packed
    slot are the refit's (density in channel 0, colour in the rest)."""
    from mi_voldis.fit import train
    ds, cfg, full, FitInputs, FitState, Adam = synthetic_object_scene(views=5)
    cfg = cfg.replace(bg_strategy="harmonic", steps_bg=2, lr_density=0.7, lr_color=0.6, tv_density=0.5,
                      tv_color=0.4, bg_lr_density=0.03, bg_lr_color=0.02, bg_tv_density=2e-3, bg_tv_color=1e-3)
    seen = []

    class Recording(train.FieldFit):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            seen.append((self.roles, self.rates, self.tv, list(self.adam.lrs["bg.packed"])))

    monkeypatch.setattr(train, "FieldFit", Recording)
    state = FitState(np.array([-1.0] * 3), np.array([1.0] * 3), Adam({}, cfg.adam_beta1, cfg.adam_beta2),
                     fields={"full": full})
    state.schedule, state.steps_full = [[0, 40]], 1
    checkpoint = str(tmp_path / "state.npz")
    state.save(checkpoint, "bg", 0)
    train.fit(ds, checkpoint, cfg, resume=True, progress=False)
    assert [(roles, rates, tv) for roles, rates, tv, _ in seen] == [(("bg",), (0.03, 0.02), (2e-3, 1e-3))]
    lrs = seen[0][3]
    assert lrs[0] == 0.03 and set(lrs[1:full.channels]) == {0.02} and not any(lrs[full.channels:])


def test_the_run_records_its_inpainter(tiny_run):
    """metrics.json's bg_prior names the 2D inpainter the default 'auto' became on this machine."""
    import json
    import os

    from mi_voldis.fit.config import FitConfig
    with open(os.path.join(tiny_run, "metrics.json")) as f:
        recorded = json.load(f)["bg_prior"]["inpainter"]
    assert recorded == resolve(FitConfig().prior_inpainter) == resolve("auto")


def test_a_blend_of_inpainters_is_the_mean_of_their_fills_and_names_its_parts(monkeypatch):
    """'a+b' fills with the mean of a's and b's fills (known pixels kept), resolves 'auto' inside it, says
    when that 'auto' falls back, and refuses an unknown part by name, in the settings as well."""
    import cv2

    from mi_voldis.fit.config import FitConfig
    from mi_voldis.inpaint2d import fallback_note
    image = np.random.default_rng(4).uniform(0, 1, (24, 30, 3)).astype(np.float32)
    hole = np.zeros((24, 30), bool)
    hole[7:15, 9:20] = True
    both = inpainter("telea+lateral")(image, hole)
    mean = (inpainter("telea")(image, hole).astype(np.float64) + inpainter("lateral")(image, hole)) / 2
    np.testing.assert_allclose(both, mean, atol=1e-6)
    assert not np.allclose(both[hole], inpainter("telea")(image, hole)[hole], atol=1e-3)
    with pytest.raises(ValueError, match="unknown inpainter 'lama'"):
        inpainter("lateral+lama")
    with pytest.raises(ValueError, match="prior_inpainter must be one of auto.*joined by '\\+'"):
        FitConfig.from_sources(None, ['prior_inpainter="lateral+lama"'])
    monkeypatch.delattr(cv2, "xphoto", raising=False)
    assert resolve("lateral+auto") == "lateral+telea" and fallback_note("lateral+auto") is not None
    assert fallback_note("lateral+telea") is None


def test_a_fit_without_its_inpainter_stops_before_fitting_anything(monkeypatch, tmp_path):
    """A prior asked to use 'fsr' needs cv2.xphoto: without it the fit says so at once, not after the
    full phase, and writes no checkpoint."""
    import cv2

    from mi_voldis.fit.train import fit
    ds, cfg, *_ = synthetic_object_scene(views=5)
    monkeypatch.delattr(cv2, "xphoto", raising=False)
    checkpoint = tmp_path / "state.npz"
    with pytest.raises(RuntimeError, match="prior_inpainter"):
        fit(ds, str(checkpoint), cfg.replace(prior_inpainter="fsr"), progress=False)
    assert not checkpoint.exists()


def sphere_over_plane_from_two_cameras():
    """A sphere above the plane y = FLOOR_Y seen by two cameras: its centre and radius, the cameras, and
    per camera the exact depth (distance along each pixel-centre ray) and the sphere's mask."""
    centre, radius = np.array([0.0, -0.1, 0.0]), 0.3
    cams = [Camera(look_at(p, [0.0, FLOOR_Y, 0.0]), 55.0, 80, 60) for p in ([0.0, 1.2, 2.0], [1.6, 1.0, 1.2])]
    depths, masks = [], []
    for cam in cams:
        py, px = np.mgrid[0:cam.height, 0:cam.width]
        o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
        ts = sphere_hit(o, d, centre, radius).reshape(cam.height, cam.width)
        masks.append(ts < plane_depth(cam))
        depths.append(np.minimum(ts, plane_depth(cam)))
    return centre, radius, cams, depths, masks


def test_visibility_of_a_plane_behind_an_occluder_from_two_cameras():
    """Plane y = -0.5, a sphere above it; the plane points behind the sphere in camera A are seen from
    camera B exactly where B's own view of them is not blocked by the sphere."""
    centre, radius, cams, depths, masks = sphere_over_plane_from_two_cameras()
    a, b = cams
    pixels = np.flatnonzero(masks[0])
    assert len(pixels) > 100
    o, d = pixel_rays(a, *(np.divmod(pixels, a.width)[::-1] + np.array(0.5)))
    points = o + plane_depth(a).reshape(-1)[pixels, None] * d
    seen = seen_elsewhere(points, [b], [depths[1]], [masks[1]])
    to_b = b.to_world[:3, 3]
    dist = np.linalg.norm(points - to_b, axis=1)
    blocked = sphere_hit(np.broadcast_to(to_b, points.shape), (points - to_b) / dist[:, None], centre, radius) < dist
    px, py, z = project(b, points)
    inside = (z > 0) & (px >= 0) & (px < b.width) & (py >= 0) & (py < b.height)
    expected = inside & ~blocked
    ix, iy = np.clip(px.astype(int), 0, b.width - 1), np.clip(py.astype(int), 0, b.height - 1)
    edge = dilate(masks[1], 2) & ~(~dilate(~masks[1], 2))  # within 2 px of B's silhouette
    clear = ~edge[iy, ix]
    assert expected[clear].any() and (~expected[clear]).any()  # both cases occur
    np.testing.assert_array_equal(seen[clear], expected[clear])


def test_space_before_the_hidden_plane_and_far_behind_it_is_voted_so_and_the_plane_itself_is_not():
    """A sphere above the plane y = -0.5, seen by two cameras, their depth maps the sphere's inside its
    masks: the plane the sphere hides is the masks' surroundings continued (a plane's disparity is
    affine: exact). Points on the way from a camera to that plane, inside the mask and more than the
    margin before it, are in front (the sphere's inside among them); points beyond (1 + behind) times
    its distance are far behind; the points about the plane are neither, those past it behind; points no
    mask holds get no vote."""
    centre, radius, cams, depths, masks = sphere_over_plane_from_two_cameras()
    a = cams[0]
    py, px = np.nonzero(masks[0] & ~dilate(~masks[0], 2))
    o, d = pixel_rays(a, px + 0.5, py + 0.5)
    floor = plane_depth(a)[py, px]
    args = (cams, [np.where(np.isfinite(x), x, np.nan) for x in depths], masks, 0, 0.05, 0.25)

    def side(t):
        return hidden_surface_side(o + t[:, None] * d, *args)

    for scale in (0.98, 1.02, 1.2):  # about the plane, just behind it, within the shell
        front, far, beyond = side(scale * floor)
        assert not front.any() and not far.any()
        assert beyond.all() if scale > 1 else not beyond.any()
    front, far, beyond = side(0.8 * floor)  # a fifth of the way short of it
    assert front.all() and not far.any() and not beyond.any()
    front, far, beyond = side(1.4 * floor)
    assert far.all() and beyond.all() and not front.any()
    inside = centre + radius * 0.5 * np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]])
    assert hidden_surface_side(inside, *args)[0].all()
    far = np.array([[3.0, 0.5, -3.0], [-2.0, 0.0, 2.5]])  # in no mask
    assert not np.any(hidden_surface_side(far, *args))


def test_the_hidden_depth_continues_the_plane_behind_not_a_pole_before_the_object():
    """A pole (a strip at a third of the sphere's depth) along the right side of camera A's mask: the
    depth filled into the mask continues the plane behind the sphere (within 1% where the plane is
    the truth), not the pole's depth."""
    centre, radius, cams, depths, masks = sphere_over_plane_from_two_cameras()
    cam, mask = cams[0], masks[0]
    depth = np.where(np.isfinite(depths[0]), depths[0], np.nan)
    ys, xs = np.nonzero(mask)
    pole = np.zeros_like(mask)
    pole[ys.min():ys.max() + 1, xs.max() + 1:xs.max() + 4] = True
    depth[pole] = depth[mask].min() / 3.0
    filled = hidden_depth(cam, depth, mask, dilate(mask, 1))
    truth = plane_depth(cam)
    inner = mask & ~dilate(~mask, 2) & np.isfinite(truth)
    assert inner.sum() > 50
    assert np.median(np.abs(filled[inner] / truth[inner] - 1.0)) < 0.01
    assert (filled[inner] > 0.8 * truth[inner]).all()


def test_the_hull_takes_in_what_an_occluder_hides_but_nothing_behind_a_surface():
    """A sphere (the object) on the plane y = -0.5 and a second sphere (an occluder) between it and
    camera B; the masks hold the object where it is visible. The object's points camera A sees that
    the occluder hides from B leave the plain hull (B votes against) but stay when B abstains, its
    depth there being nearer (:func:`~mi_voldis.fit.hull.visual_hull` with depths); points inside the
    floor under the object, hidden from both views, can win that vote too, and the surface test of
    :func:`~mi_voldis.fit.hull.hull_behind_occluders` keeps them out; floor points B sees stay out."""
    from mi_voldis.fit.hull import hull_behind_occluders, visual_hull
    obj, r_obj = np.array([0.0, FLOOR_Y + 0.2, 0.0]), 0.2
    occ, r_occ = np.array([1.0, FLOOR_Y + 0.22, 0.1]), 0.12
    cams = [Camera(look_at(p, obj), 50.0, 80, 60) for p in ([0.0, 1.2, 2.0], [2.2, FLOOR_Y + 0.3, 0.2])]
    depths, masks = [], []
    for cam in cams:
        py, px = np.mgrid[0:cam.height, 0:cam.width]
        o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
        t_obj = sphere_hit(o, d, obj, r_obj).reshape(cam.height, cam.width)
        t_occ = sphere_hit(o, d, occ, r_occ).reshape(cam.height, cam.width)
        depth = np.minimum(np.minimum(t_obj, t_occ), plane_depth(cam))
        masks.append(t_obj <= depth)
        depths.append(np.where(np.isfinite(depth), depth, np.nan))
    masks = np.stack(masks)
    a, b = cams
    pixels = np.flatnonzero(masks[0])
    o, d = pixel_rays(a, *(np.divmod(pixels, a.width)[::-1] + np.array(0.5)))
    points = o + depths[0].reshape(-1)[pixels, None] * d  # the object's surface A sees
    to_b = b.to_world[:3, 3]
    dist = np.linalg.norm(points - to_b, axis=1)
    hidden = sphere_hit(np.broadcast_to(to_b, points.shape), (points - to_b) / dist[:, None], occ, r_occ) < dist
    ix, iy, framed = pixel_of(b, points)
    hidden &= framed & ~dilate(masks[1], 1)[np.clip(iy, 0, b.height - 1), np.clip(ix, 0, b.width - 1)]
    assert hidden.sum() > 20 and (~hidden).sum() > 20  # the occluder hides part of the object from B
    plain = visual_hull(points, cams, masks, 0, 0.9)
    assert not plain[hidden].any()
    assert hull_behind_occluders(points, cams, masks, 0, 0.9, depths)[hidden].all()
    # inside the floor, under the object: hidden from both views
    g = np.stack(np.meshgrid(np.linspace(-0.08, 0.08, 5), np.linspace(-0.08, 0.08, 5)), -1).reshape(-1, 2)
    under = np.stack([g[:, 0], np.full(len(g), FLOOR_Y - 0.05), g[:, 1]], axis=1)
    assert visual_hull(under, cams, masks, 0, 0.9, depths).sum() > 5  # A's mask holds them, B abstains
    assert not hull_behind_occluders(under, cams, masks, 0, 0.9, depths).any()
    # on the floor beside the object, where B sees the floor unmasked
    floor = np.flatnonzero((depths[1] == plane_depth(b)).reshape(-1))
    o, d = pixel_rays(b, *(np.divmod(floor, b.width)[::-1] + np.array(0.5)))
    beside = o + depths[1].reshape(-1)[floor, None] * d
    beside = beside[np.linalg.norm(beside[:, [0, 2]] - obj[[0, 2]], axis=1) < 0.5]
    assert len(beside) > 20
    assert not hull_behind_occluders(beside, cams, masks, 0, 0.9, depths).any()


def test_held_out_pixels_split_by_what_training_views_see():
    """The benchmark's split of a held-out view's masked pixels: the plane behind the sphere in camera A
    counts as seen exactly where camera B sees it unmasked; pixels without depth or outside the region
    never do."""
    from types import SimpleNamespace

    from mi_voldis.bench.visible import seen_pixels
    centre, radius, cams, depths, masks = sphere_over_plane_from_two_cameras()
    ds = SimpleNamespace(cameras=cams, masks=masks)
    behind = plane_depth(cams[0])
    behind[:10] = np.nan  # no background depth there
    got = seen_pixels(ds, 0, masks[0], behind, {1: depths[1]})
    pixels = np.flatnonzero(masks[0] & np.isfinite(behind))
    o, d = pixel_rays(cams[0], *(np.divmod(pixels, cams[0].width)[::-1] + np.array(0.5)))
    expected = seen_elsewhere(o + behind.reshape(-1)[pixels, None] * d, [cams[1]], [depths[1]], [masks[1]])
    assert expected.any() and (~expected).any()
    np.testing.assert_array_equal(got.reshape(-1)[pixels], expected)
    assert not got[~masks[0]].any() and not got[:10].any()


def empty_world_field(resolution=40):
    lo, hi = np.array([-1.0, -1.0, -1.0]), np.array([1.0, 1.0, 1.0])
    voxel = 2.0 / (resolution - 1)
    return new_field(lo, hi, resolution, 0, -20.0, 1.0 / voxel), SceneSpace("world")


def test_a_lifted_surface_looks_the_same_from_every_view():
    """A textured patch lifted from camera A onto the plane y = -0.5 renders in camera B as A's pixels
    reprojected through that plane: two views of the lifted region agree."""
    field, space = empty_world_field()
    a = Camera(look_at([0.0, 1.0, 1.8], [0.0, FLOOR_Y, 0.0]), 50.0, 48, 36)
    b = Camera(look_at([1.2, 0.8, 1.2], [0.0, FLOOR_Y, 0.0]), 50.0, 48, 36)
    region = np.zeros((a.height, a.width), bool)
    region[8:28, 10:38] = True
    yy, xx = np.mgrid[0:a.height, 0:a.width]
    colors = np.stack([0.2 + 0.6 * xx / a.width, 0.3 + 0.5 * yy / a.height, np.full(xx.shape, 0.5)], -1)
    points, rgb = lift_pixels(a, region, plane_depth(a), colors)
    lifted, keys = write_surface(field, space, points, rgb, lambda f: dr.full(mi.Float, 1.0, f.vertices))
    assert len(keys) > 0
    props = integrator_properties(space, samples=256, step_size=0.25 * 2.0 / 39)
    integ = build_integrator({"full": lifted.plugin(), "bg": lifted.plugin()}, props)
    in_a = render_camera(integ, a, ("full",))["full"]
    inner = region & ~dilate(~region, 2)
    assert in_a[1][inner].min() > 0.95  # opaque where lifted
    assert np.abs(in_a[0][inner] - colors[inner]).mean() < 0.04
    in_b = render_camera(integ, b, ("full",))["full"]
    py, px = np.mgrid[0:b.height, 0:b.width]
    o, d = pixel_rays(b, px.ravel() + 0.5, py.ravel() + 0.5)
    hit = o + plane_depth(b).reshape(-1, 1) * d
    u, v, z = project(a, hit)
    ok = (z > 0) & (u >= 0) & (u < a.width) & (v >= 0) & (v < a.height)
    ok[ok] &= inner[v[ok].astype(int), u[ok].astype(int)]
    assert ok.sum() > 100
    expected = colors[v[ok].astype(int), u[ok].astype(int)]
    got = in_b[0].reshape(-1, 3)[ok]
    assert np.abs(got - expected).mean() < 0.05
    # nowhere allowed (no lifted point in the object's hull): the field's values stay, no key is written
    kept, none = write_surface(field, space, points, rgb, lambda f: dr.zeros(mi.Float, f.vertices))
    assert len(none) == 0 and np.array_equal(np.unique(np.array(kept.data)), np.unique(np.array(field.data)))


SHADOW = (np.array([0.55, 0.0]), 0.15)  # centre (x, z) and radius of the sphere's shadow on the floor
CONTACT = 0.31  # radius about the sphere's foot (x = z = 0) of its contact shadow on the floor


def synthetic_object_scene(views=10, size=(40, 30), hidden_floor=False, sphere_raw=4.0, empty=-20.0, shadow=False,
                           contact=False):
    """A textured floor with a red sphere standing on it: the photos rendered from the truth, with exact
    masks and the ground-truth background (the floor alone), and as the fitted full field the truth
    plus a faint red haze around the sphere, as fits leave; ``hidden_floor``: without the floor under
    the sphere's footprint, which no photo shows (a fit leaves nothing there); ``sphere_raw``: the
    sphere's raw density (the floor's is 4); ``empty``: the raw density of empty space in the full
    field (a fit leaves about -7, opacity 1e-3 per voxel, where the gradient still flows); ``shadow``:
    the floor darkened in a disc beside the sphere (:data:`SHADOW`) in the photos and the full field but
    not in the ground-truth background, and the dataset's effect masks where the photos differ from it;
    ``contact``: the floor darkened within :data:`CONTACT` of the sphere's foot the same way (its contact
    shadow, which views see beside its silhouette), without effect masks."""
    from mi_voldis.fit.fields import FitInputs
    from mi_voldis.fit.state import FitState
    from mi_voldis.optim.adam import Adam
    lo, hi = np.array([-1.0, -1.0, -1.0]), np.array([1.0, 1.0, 1.0])
    res = 40
    voxel = 2.0 / (res - 1)
    fields = {name: new_field(lo, hi, res, 0, -20.0, 1.0 / voxel) for name in ("full", "truth", "floor")}
    full = fields["full"]
    pts, real = vertex_positions(full)
    centre, radius = np.array([0.0, FLOOR_Y + 0.3, 0.0]), 0.3
    r = np.linalg.norm(pts - centre, axis=1)
    is_floor = (np.abs(pts[:, 1] - FLOOR_Y) < 1.5 * voxel) & real
    texture = np.stack([0.3 + 0.3 * (np.sin(6 * pts[:, 0]) > 0), 0.5 + 0.2 * np.cos(5 * pts[:, 2]),
                        np.full(len(pts), 0.35)], -1)
    shade = np.where(shadow & (np.hypot(pts[:, 0] - SHADOW[0][0], pts[:, 2] - SHADOW[0][1]) < SHADOW[1]), 0.4, 1.0)
    shade *= np.where(contact & (np.hypot(pts[:, 0], pts[:, 2]) < CONTACT), 0.4, 1.0)
    dense, haze = 4.0, -3.0  # haze: about 13% opaque across its three voxels
    width = full.width
    out = {}
    for name, field in fields.items():
        values = np.array(field.data).reshape(-1, width)
        block = values[: full.layout.vertices_per_brick].copy()
        values[:, 0] = np.where(is_floor, dense, empty if name == "full" else -20.0)
        tint = texture * (shade[:, None] if name != "floor" else 1.0)
        values[:, 1:4] = np.where(is_floor[:, None], np.log(tint / (1 - tint)), -10.0)
        if name != "floor":
            obj = (r < radius) & real
            fog = (r >= radius) & (r < radius + 3 * voxel) & real & ~is_floor & (name == "full")
            values[obj | fog, 1:4] = np.log(np.array([0.9, 0.1, 0.1]) / np.array([0.1, 0.9, 0.9]))
            values[obj, 0] = sphere_raw
            values[fog, 0] = haze
            if hidden_floor and name == "full":
                values[is_floor & (np.hypot(pts[:, 0] - centre[0], pts[:, 2] - centre[2]) < radius), 0] = empty
        values[: full.layout.vertices_per_brick] = block
        field.data = from_numpy(mi.Float, values.ravel())
        out[name] = field
    cams = orbit(views, [0.0, FLOOR_Y, 0.0], 1.7, (50, 65), 40.0, *size)
    space = SceneSpace("world")
    props = integrator_properties(space, samples=256, step_size=0.5 * voxel)
    render = {k: build_integrator({"full": f.plugin(), "bg": f.plugin()}, props) for k, f in out.items()}
    images, backgrounds, masks = [], [], []
    for cam in cams:
        rgb, alpha, _ = render_camera(render["truth"], cam, ("full",))["full"]
        assert alpha.min() > 0.99  # a closed scene: every ray ends on the floor or the sphere
        images.append(np.clip(rgb, 0, 1))
        backgrounds.append(np.clip(render_camera(render["floor"], cam, ("full",))["full"][0], 0, 1))
        py, px = np.mgrid[0:cam.height, 0:cam.width]
        o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
        masks.append((sphere_hit(o, d, centre, radius) < plane_depth(cam).reshape(-1)).reshape(cam.height, cam.width))
    split = np.array(["test" if k % 5 == 0 else "train" for k in range(views)])
    ds = Dataset("synthetic", "", [f"v{k}" for k in range(views)], np.array(images, np.float32), cams, split,
                 SceneBox("world", lo, hi), masks=np.array(masks), backgrounds=np.array(backgrounds, np.float32),
                 meta={"aabb": [lo.tolist(), hi.tolist()], "format": "synthetic"})
    if shadow:
        ds.effects = (np.abs(ds.images - ds.backgrounds).max(-1) > 0.02) & ~ds.masks
    cfg = FitConfig.from_sources(None, ["space=\"world\"", "steps_bg=0", "max_samples=256", "prior_inpainter=\"telea\"",
                                        "resolution_schedule=[[0,40]]", "steps_full=1"])
    return ds, cfg, out["full"], FitInputs, FitState, Adam


@pytest.mark.parametrize("strategy", ["lift", "clear"])
def test_removal_leaves_nothing_of_the_object(strategy, tmp_path):
    """No density of the object survives in the background (nor, in renders, its colour from the haze),
    the background equals the full field away from the masks, and with the lifted prior the renders
    inside the masks show the floor, not the object."""
    from mi_voldis.field.state import density_of, density_raw_for_alpha
    from mi_voldis.fit.fields import fit_integrator
    from mi_voldis.fit.train import fit
    ds, cfg, full, FitInputs, FitState, Adam = synthetic_object_scene()
    cfg = cfg.replace(bg_strategy=strategy)
    adam = Adam({}, cfg.adam_beta1, cfg.adam_beta2)
    state = FitState(np.array([-1.0] * 3), np.array([1.0] * 3), adam, fields={"full": full})
    state.schedule, state.steps_full = [[0, 40]], 1
    checkpoint = str(tmp_path / "state.npz")
    state.save(checkpoint, "bg", 0)
    inputs, state = fit(ds, checkpoint, cfg, resume=True, progress=False)
    bg = state.fields["bg"]
    pts, real = vertex_positions(bg)
    voxel = 2.0 / 39
    centre = np.array([0.0, FLOOR_Y + 0.3, 0.0])
    inside = real & (np.linalg.norm(pts - centre, axis=1) < 0.3) & (pts[:, 1] > FLOOR_Y + 3 * voxel)
    assert inside.sum() > 100
    assert density_of(bg)[inside].max() < density_raw_for_alpha(0.01, voxel, bg.density_scale)
    integ = fit_integrator(inputs, state)
    for v in ds.test:
        layers = render_camera(integ, ds.cameras[v], ("full", "bg"))
        out, mask = ~dilate(ds.masks[v], 4), ds.masks[v]
        # what views see stays (the lifted surface's rim, inside the grown hull, may tint the floor beside it)
        assert np.abs(layers["bg"][0][out] - layers["full"][0][out]).mean() < (0.015 if strategy == "lift" else 0.01)
        if strategy == "lift":
            removed = np.clip(layers["bg"][0], 0, 1)
            assert object_residue(removed, ds.images[v], ds.backgrounds[v], mask) < 0.1
            error = np.abs(removed[mask] - ds.backgrounds[v][mask]).mean()
            assert error < 0.5 * np.abs(ds.images[v][mask] - ds.backgrounds[v][mask]).mean()
    if strategy == "lift":
        assert set(state.prior["reference_views"]) <= set(ds.train.tolist())
        assert state.prior["vertices_written"] > 0 and state.prior["inpainter"] == "telea"


def sphere_seen_unmasked(ds, pts, voxel, centre, radius=0.3, grow=1):
    """Per point: some masked training view has it in view outside its mask grown by a pixel, the ray
    to it not through the sphere (analytic visibility on :func:`synthetic_object_scene`)."""
    seen = np.zeros(len(pts), bool)
    for v in ds.masked_train:
        cam = ds.cameras[v]
        px, py, z = project(cam, pts)
        ix, iy = np.floor(px).astype(int), np.floor(py).astype(int)
        ok = (z > 0) & (ix >= 0) & (ix < cam.width) & (iy >= 0) & (iy < cam.height)
        ok[ok] &= ~dilate(ds.masks[v], grow)[iy[ok], ix[ok]]
        o = np.broadcast_to(cam.to_world[:3, 3], pts.shape)
        dist = np.linalg.norm(pts - o, axis=1)
        seen |= ok & ~(sphere_hit(o, (pts - o) / dist[:, None], centre, radius) < dist - voxel)
    return seen


def guided_removal(tmp_path, shadow=False, effects=True, contact=False, edit=None, **settings):
    """The synthetic sphere's full field and the inputs and state after the guided background refit;
    ``shadow``: with the sphere's shadow (:func:`synthetic_object_scene`), given as effect masks if
    ``effects``; ``contact``: with its contact shadow; ``edit``: the full field made another by this
    function of (dataset, full field) first."""
    from mi_voldis.fit.train import fit
    ds, cfg, full, FitInputs, FitState, Adam = synthetic_object_scene(shadow=shadow, contact=contact)
    full = full if edit is None else edit(ds, full)
    ds.effects = ds.effects if effects else None
    cfg = cfg.replace(**{"bg_strategy": "guided", "steps_bg": 30, **settings})
    state = FitState(np.array([-1.0] * 3), np.array([1.0] * 3), Adam({}, cfg.adam_beta1, cfg.adam_beta2),
                     fields={"full": full})
    state.schedule, state.steps_full = [[0, 40]], 1
    checkpoint = str(tmp_path / "state.npz")
    state.save(checkpoint, "bg", 0)
    return (ds, full) + fit(ds, checkpoint, cfg, resume=True, progress=False)


def test_the_floor_under_the_object_starts_whole_when_the_hull_is_filled_along_the_horizontal(tmp_path):
    """The sphere on its floor (the floor under it in the full field too, as the truth has it): the
    guided background's start (no refit step) fills the hull, the floor vertices under the sphere among
    it. Filled along the horizontal (the cameras' up is +y) they take the floor's raw density 4 from the
    floor around the hull; the isotropic fill mixes in the air above and leaves a translucent hole."""
    from mi_voldis.field.state import density_of
    floors = {}
    for vertical in (0.0, 1.0):
        _, _, _, state = guided_removal(tmp_path / str(vertical), steps_bg=0, hull_fill_vertical=vertical)
        bg = state.fields["bg"]
        pts, real = vertex_positions(bg)
        under = real & (np.hypot(pts[:, 0], pts[:, 2]) < 0.25) & (np.abs(pts[:, 1] - FLOOR_Y) < 0.5 * 2.0 / 39)
        assert under.sum() > 50
        floors[vertical] = density_of(bg)[under]
    np.testing.assert_allclose(floors[0.0], 4.0, atol=1e-3)
    assert np.median(floors[1.0]) < 0.0


def test_the_fill_finds_the_up_at_the_object_when_its_hull_runs_out_to_the_far_shell():
    """A one-sided rig's unseen hull runs from the object out to a contracted space's far shell. The fill's
    axis weights carry the world's up (+y: the ring of level cameras) into the lattice where the object is:
    inside the linear cube the contraction is the identity, so the weights are 1 along x and z and 0 along
    y, however far the hull's tail reaches. Read at the tail's mean, far out in the shell, the radial squeeze
    there would tilt the up towards the tail."""
    from types import SimpleNamespace

    from mi_voldis.field.spec import box_transform
    from mi_voldis.fit.background import fill_weights
    rng = np.random.default_rng(0)
    space = SceneSpace("contract", np.eye(4), shell=1.0)
    cams = [Camera(look_at([3 * np.sin(a), 0.5, 3 * np.cos(a)], [0, 0, 0]), 50.0, 32, 24)
            for a in np.linspace(0, 2 * np.pi, 8, endpoint=False)]
    inputs = SimpleNamespace(cfg=SimpleNamespace(hull_fill_vertical=0.0), space=space,
                             ds=SimpleNamespace(cameras=cams, train=np.arange(8)))
    field = SimpleNamespace(to_world=box_transform([-2.0] * 3, [2.0] * 3), shape=(65, 65, 65))
    cluster = np.array([0.2, 0.0, 0.1]) + rng.uniform(-0.2, 0.2, (2000, 3))
    tail = np.array([0.2, 0.0, 0.1]) + np.geomspace(1.0, 1e9, 1500)[:, None] * np.array([0.1, -1.0, 0.4])
    points = space.from_world_np(np.concatenate([cluster, tail]))
    np.testing.assert_allclose(fill_weights(inputs, field, points), [1, 1, 0, 0, 1, 1], atol=1e-6)


def test_a_shadow_given_as_effect_masks_leaves_with_the_object_and_the_floor_keeps_its_geometry(tmp_path):
    """The sphere's shadow on the floor, given as effect masks: the guided refit fits no ray of it to the
    photos (the ray pool leaves its pixels out) and draws it from the prior, so on the held-out views
    the background there is nearer the unshadowed truth than the photos are and than the background
    fitted without them, while no floor vertex under the shadow outside the object's hull changes its
    density: only its colour (brighter)."""
    from mi_voldis.field.state import density_of, neighbour_vertices
    from mi_voldis.fit.background import background_ray_pool, hull_region
    from mi_voldis.fit.fields import fit_integrator
    errors, shadow = {}, None
    for given in (False, True):
        ds, full, inputs, state = guided_removal(tmp_path / str(given), shadow=True, effects=given, steps_bg=150,
                                                 shadow_contrast=0.0)  # without: no shadow search either
        shadow = shadow if ds.effects is None else ds.effects
        bg = fit_integrator(inputs, state)
        errors[given] = [np.abs(np.clip(render_camera(bg, ds.cameras[v], ("bg",))["bg"][0], 0, 1)
                                - ds.backgrounds[v]) for v in ds.test]
    assert all(shadow[v].sum() > 20 for v in ds.test)
    errors = {k: np.mean([e[shadow[v]].mean() for e, v in zip(errs, ds.test)]) for k, errs in errors.items()}
    photos = np.mean([np.abs(ds.images[v] - ds.backgrounds[v])[shadow[v]].mean() for v in ds.test])
    assert errors[True] < 0.6 * errors[False] and errors[True] < 0.9 * photos, (errors, photos)
    pool = background_ray_pool(ds, inputs.bank, inputs.cfg.bg_ray_dilation, ds.effects)
    assert not (ds.effects[inputs.bank.views] | ds.masks[inputs.bank.views]).reshape(-1)[pool].any()
    pts, real = vertex_positions(full)
    hull = np.array(hull_region(inputs, full, neighbour_vertices(full))[0]) > 0
    under = real & ~hull & (np.abs(pts[:, 1] - FLOOR_Y) < 1.5 * 2.0 / 39) & \
        (np.hypot(pts[:, 0] - SHADOW[0][0], pts[:, 2] - SHADOW[0][1]) < SHADOW[1])
    assert under.sum() > 10
    assert np.array_equal(density_of(state.fields["bg"])[under], density_of(full)[under])
    colour = np.array(state.fields["bg"].data).reshape(-1, full.width)[:, 1:4]
    assert (colour[under] > np.array(full.data).reshape(-1, full.width)[under, 1:4]).mean() > 0.5  # brighter


def test_the_contact_shadow_beside_the_silhouette_leaves_with_the_object(tmp_path):
    """The sphere's contact shadow (the floor 60% darker within :data:`CONTACT` of its foot, not in the
    truth) shows just below its silhouette in the photos, where no mask covers it. Every pixel of the dark
    fringe found there is one the object changed (the photo off the truth). They leave L_bg for the prior:
    on the held-out views' own fringe (:func:`~mi_voldis.fit.fringe.dark_fringe`) the background is nearer
    the truth than the one fitted without it and than the photos. With ``fringe_unseen`` no view counts as
    seeing the background through them (more of the hull is refilled). Without a contact shadow a few
    pixels of the sphere's soft edge are found, not the textured floor."""
    import dataclasses

    from mi_voldis.fit.background import background_ray_pool, background_regions
    from mi_voldis.fit.fields import fit_integrator
    from mi_voldis.fit.fringe import dark_fringe
    errors, photos = {}, None
    for contrast in (0.0, 0.1):
        ds, full, inputs, state = guided_removal(tmp_path / str(contrast), contact=True, steps_bg=100,
                                                 shadow_contrast=0.0, fringe_contrast=contrast)
        bg = fit_integrator(inputs, state)
        fringes = {v: dark_fringe(ds.images[v], ds.masks[v], 2, 0.1) for v in ds.test}
        errors[contrast] = np.mean([np.abs(np.clip(render_camera(bg, ds.cameras[v], ("bg",))["bg"][0], 0, 1)
                                           - ds.backgrounds[v])[fringes[v]].mean() for v in ds.test])
        photos = np.mean([np.abs(ds.images[v] - ds.backgrounds[v])[fringes[v]].mean() for v in ds.test])
    record, fringe = state.prior["fringe"], inputs.ds.effects
    assert record["pixels"] > 50 and record["views"] >= len(ds.masked_train) // 2, record
    changed = np.abs(ds.images - ds.backgrounds).max(-1) > 0.05
    assert not (fringe & ~changed).any()
    pool = background_ray_pool(ds, inputs.bank, inputs.cfg.bg_ray_dilation, fringe)
    assert not fringe[inputs.bank.views].reshape(-1)[pool].any()
    assert errors[0.1] < 0.9 * errors[0.0] and errors[0.1] < 0.7 * photos, (errors, photos)
    # with fringe_unseen (the default) no view sees the background through the fringe: the hull vertices
    # seen only there are refilled too; without it the hull is divided as without a fringe
    assert inputs.fringe is not None and np.array_equal(inputs.fringe, fringe)
    refilled = {k: np.array(background_regions(dataclasses.replace(inputs, fringe=f, cfg=cfg), state)[3])
                for k, f, cfg in (("default", inputs.fringe, inputs.cfg), ("without", None, inputs.cfg),
                                  ("kept", inputs.fringe, inputs.cfg.replace(fringe_unseen=False)))}
    assert (refilled["default"] >= refilled["without"]).all()
    assert refilled["default"].sum() > refilled["without"].sum()
    assert np.array_equal(refilled["kept"], refilled["without"])
    _, _, _, state = guided_removal(tmp_path / "none", steps_bg=0, shadow_contrast=0.0)
    assert state.prior["fringe"]["pixels"] < 0.2 * record["pixels"], (state.prior["fringe"], record)


def test_the_denser_of_two_fields_takes_the_density_alone_and_only_in_its_region():
    """:func:`~mi_voldis.fit.background.denser` on packed values of width 3 (density, two colours): in
    the region the density is the larger of the two, everywhere else and in every colour channel the
    filled values'; the kept values are not written."""
    from mi_voldis.fit.background import denser
    kept = np.array([1.0, 9.0, 9.0, 5.0, 9.0, 9.0, -2.0, 9.0, 9.0, 3.0, 9.0, 9.0])
    filled = np.array([2.0, 0.1, 0.2, 4.0, 0.3, 0.4, -3.0, 0.5, 0.6, 0.0, 0.7, 0.8])
    before = mi.Float(kept)
    out = np.array(denser(before, mi.Float(filled), 3, mi.Bool([True, True, False, True])))
    np.testing.assert_array_equal(out, np.float32([2.0, 0.1, 0.2, 5.0, 0.3, 0.4, -3.0, 0.5, 0.6, 3.0, 0.7, 0.8]))
    np.testing.assert_array_equal(np.array(before), kept)


def test_what_views_see_only_through_the_fringe_is_refilled_but_never_thinned(tmp_path):
    """The sphere's contact shadow is its fringe. The hull vertices that views see unmasked only through
    it (:func:`~mi_voldis.fit.background.fringe_vertices`: the sphere's soft edge and the floor by its
    foot) start the background refilled: in colour the hull's fill, in density the larger of the full
    field's and the fill's. The floor among them (raw density 4, as the fill continues it) is made
    alternately denser (8: a lip the fill would thin, moving the surface behind the full field's so that
    the foreground, the sample-wise max(w_full - w_bg, 0), would spill onto it; it stays) and thinner
    (1: the outline's thinned floor, which the fill mends). With ``fringe_unseen`` off they start as the
    full field holds them, but for those within ``keep_seen_gap`` of the object's voxels."""
    from mi_voldis.field.state import density_of, neighbour_vertices
    from mi_voldis.fit.background import (
        background_regions,
        fill_weights,
        fringe_vertices,
        harmonic_fill,
        start_harmonic,
    )
    ds, full, inputs, state = guided_removal(tmp_path, contact=True, steps_bg=0, shadow_contrast=0.0)
    assert inputs.fringe is not None and inputs.cfg.fringe_unseen  # the default
    neighbours = neighbour_vertices(full)
    hull, _, obj, _ = background_regions(inputs, state, neighbours)
    edge = np.array(fringe_vertices(inputs, state, hull, {})) & ~np.array(obj)
    floor = np.flatnonzero(edge & (np.abs(density_of(full) - 4.0) < 1e-3))
    assert len(floor) > 20, len(floor)
    data = np.array(full.data).reshape(-1, full.width)
    data[floor[0::2], 0], data[floor[1::2], 0] = 8.0, 1.0
    state.fields["full"] = full = full.with_data(mi.Float(data.reshape(-1)))
    starts = {}
    for unseen in (False, True):
        start_harmonic(dataclasses.replace(inputs, cfg=inputs.cfg.replace(fringe_unseen=unseen)), state)
        starts[unseen] = state.fields["bg"]
    hull, points, obj, refill = background_regions(inputs, state, neighbours)
    edge = np.array(fringe_vertices(inputs, state, hull, {})) & ~np.array(obj)
    plain = harmonic_fill(full.bricks_data(), full.width, dr.select(refill, hull, 0.0), neighbours,
                          weights=fill_weights(inputs, full, points))
    plain = np.array(plain).reshape(-1, full.width)[:full.vertices]
    kept, refilled = density_of(full), density_of(starts[True])
    lip, thin = np.intersect1d(floor[0::2], np.flatnonzero(edge)), np.intersect1d(floor[1::2], np.flatnonzero(edge))
    assert len(lip) > 10 and len(thin) > 10, (len(lip), len(thin))
    assert (plain[lip, 0] < 7.0).mean() > 0.5 and (plain[thin, 0] > 2.0).mean() > 0.5  # what the fill alone does
    np.testing.assert_allclose(refilled[edge], np.maximum(kept, plain[:, 0])[edge], atol=1e-5)
    np.testing.assert_allclose(refilled[lip], 8.0, atol=1e-5)
    colour = np.array(starts[True].data).reshape(-1, full.width)[:full.vertices]
    np.testing.assert_allclose(colour[edge, 1:4], plain[edge, 1:4], atol=1e-5)
    assert np.abs(colour[edge, 1:4] - data[:full.vertices][edge, 1:4]).max() > 0.1
    off = dataclasses.replace(inputs, cfg=inputs.cfg.replace(fringe_unseen=False))
    kept_off = edge & ~np.array(background_regions(off, state, neighbours)[3])  # not the object's soft edge
    assert kept_off.sum() > 0.5 * edge.sum()
    np.testing.assert_array_equal(density_of(starts[False])[kept_off], kept[kept_off])


def test_a_shadow_no_light_explains_is_not_searched_into_the_removal(tmp_path):
    """The synthetic sphere is one flat colour, lit by nothing (no side of it brighter), and its
    'shadow' a disc on the floor: no light is kept, the search's record says why, and the background
    is the one fitted with the search off (to the rounding of the adjoint's scatter-adds, which run in
    any order)."""
    runs = {}
    for contrast in (0.0, 0.5):
        ds, full, inputs, state = guided_removal(tmp_path / str(contrast), shadow=True, effects=False,
                                                 shadow_contrast=contrast)
        runs[contrast] = (np.array(state.fields["bg"].data), state.prior)
    record = runs[0.5][1]["shadow"]
    assert record is not None and not record["kept"] and record["shading"] < 0.1
    assert "shadow" not in (runs[0.0][1] or {})
    np.testing.assert_allclose(runs[0.5][0], runs[0.0][0], atol=1e-4)  # two runs of either differ by ~1e-6


def test_what_some_view_sees_keeps_the_full_fields_density_so_the_foreground_is_the_object_alone(tmp_path):
    """With ``keep_seen`` the guided refit leaves the full field's density at every vertex
    a training view sees unmasked (analytically: above the floor, outside the view's mask grown by 3
    pixels, the way to it not through the sphere), so on the training views away from the masks the
    foreground coverage sum max(w_fg, 0) is nil (above 0.1 on under 1% of those pixels); the harmonic
    fill without it reshapes those vertices and the coverage spills there."""
    from mi_voldis.field.state import density_of
    from mi_voldis.fit.fields import fit_integrator
    voxel, centre = 2.0 / 39, np.array([0.0, FLOOR_Y + 0.3, 0.0])
    results = {}
    for keep in (True, False):
        ds, full, inputs, state = guided_removal(tmp_path / str(keep), keep_seen=keep, keep_seen_gap=0)
        pts, real = vertex_positions(full)
        seen = real & (pts[:, 1] > FLOOR_Y + 0.5 * voxel) & sphere_seen_unmasked(ds, pts, voxel, centre, grow=3)
        changed = np.abs(density_of(state.fields["bg"]) - density_of(full))[seen]
        integ = fit_integrator(inputs, state)
        spill = [render_camera(integ, ds.cameras[v], ("fg",))["fg_coverage"][~dilate(ds.masks[v], 3)]
                 for v in ds.masked_train]
        results[keep] = changed, np.concatenate(spill)
    changed, spill = results[True]
    assert len(changed) > 1000 and changed.max() == 0.0
    assert spill.mean() < 0.005 and (spill > 0.1).mean() < 0.01
    changed, spill = results[False]
    assert (changed > 0.5).sum() > 100
    assert spill.mean() > 0.05 and (spill > 0.1).mean() > 0.1


def test_the_haze_views_see_through_leaves_the_background_and_never_thickens(tmp_path, monkeypatch):
    """``seen_surface_tol``: a veil of haze hung in the sphere's hull (raw density -1 and -4 at alternate
    vertices, 4.5 voxels and more from the sphere and 2.5 above the floor: beyond ``keep_seen_gap`` and the
    object's own voxels), where training views see it unmasked and look through it to the floor, is kept
    vertex for vertex when every seen vertex keeps the full field's density (tolerance 0, the default). At
    0.015 those vertices lie on no view's surface: the refit takes them with the hole, the veil thinned to under
    half its density on the whole, and no vertex of it denser than the full field holds it. The fill alone
    already leaves it so (the refit's clamp, :func:`~mi_voldis.fit.background.no_denser`, switched off, no
    refit step): a plain harmonic fill would even the alternation out, the -4 vertices denser than before."""
    from mi_voldis.field.state import density_of
    from mi_voldis.fit.background import background_regions
    voxel, centre, radius = 2.0 / 39, np.array([0.0, FLOOR_Y + 0.3, 0.0]), 0.3
    veils = {}

    def veiled(ds, full):
        pts, real = vertex_positions(full)
        r = np.linalg.norm(pts - centre, axis=1)
        veil = (real & (pts[:, 1] > FLOOR_Y + 2.5 * voxel) & (r > radius + 4.5 * voxel)
                & sphere_seen_unmasked(ds, pts, voxel, centre, grow=3))
        data = np.array(full.data).reshape(-1, full.width)
        data[:full.vertices][veil, 0] = np.where(np.flatnonzero(veil) % 2 == 0, -1.0, -4.0)
        veils["all"] = veil
        return full.with_data(mi.Float(data.reshape(-1)))
    results = {}
    for tol in (0.0, 0.015):
        ds, full, inputs, state = guided_removal(tmp_path / str(tol), edit=veiled, seen_surface_tol=tol)
        if tol == 0.0:  # the veil's vertices in the hull that are kept as seen (not refilled with the hole)
            hull, _, _, refill = background_regions(inputs, state)
            veils["kept"] = veils["all"] & (np.array(hull) > 0) & ~np.array(refill)
        veil = veils["kept"]
        results[tol] = density_of(state.fields["bg"])[veil], density_of(full)[veil]
    bg, fu = results[0.0]
    assert len(fu) > 200 and np.array_equal(bg, fu)
    bg, fu = results[0.015]
    assert np.all(bg <= fu)
    assert np.logaddexp(0, bg).mean() < 0.5 * np.logaddexp(0, fu).mean()  # softplus: the density
    monkeypatch.setattr("mi_voldis.fit.train.no_denser", lambda field, reference, region: field)
    _, full, _, state = guided_removal(tmp_path / "start", edit=veiled, seen_surface_tol=0.015, steps_bg=0)
    bg, fu = density_of(state.fields["bg"])[veils["kept"]], density_of(full)[veils["kept"]]
    assert np.all(bg <= fu) and np.any(bg < fu)


def test_no_denser_caps_the_density_alone_and_only_in_its_region():
    """:func:`~mi_voldis.fit.background.no_denser`: a field and a reference on one lattice; in the region
    the density is the smaller of the two, everywhere else and in every colour channel the field's own."""
    from mi_voldis.field.state import density_of
    from mi_voldis.fit.background import no_denser
    field = new_field(np.zeros(3), np.ones(3), 8, 0, -3.0, 1.0, 4)
    rng = np.random.default_rng(1)
    mine = rng.normal(0, 2, dr.width(field.data)).astype(np.float32)
    theirs = rng.normal(0, 2, dr.width(field.data)).astype(np.float32)
    a, b = field.with_data(mi.Float(mine)), field.with_data(mi.Float(theirs))
    region = rng.random(field.vertices) < 0.5
    out = no_denser(a, b, mi.Bool(region))
    da, db, do = density_of(a), density_of(b), density_of(out)
    np.testing.assert_array_equal(do[region], np.minimum(da, db)[region])
    np.testing.assert_array_equal(do[~region], da[~region])
    assert np.any(db[region] < da[region])
    colour = np.array(out.bricks_data()).reshape(-1, field.width)[:, 1:]
    np.testing.assert_array_equal(colour, np.array(a.bricks_data()).reshape(-1, field.width)[:, 1:])


def test_the_objects_soft_edge_leaves_with_it_though_views_see_it_unmasked(tmp_path):
    """``keep_seen_gap``: the sphere's haze (three voxels thick outside it, as fits leave) is seen
    unmasked beside its silhouette, so ``keep_seen`` alone keeps its density in the background, where
    the foreground w_fg = w_full - w_bg misses it; with a gap of 4 vertices round the object's voxels
    the haze is refilled like the unseen hull (its opacity falls to under half the haze's), while
    what views see unmasked beyond the gap (more than 8 voxels from the sphere: the object's voxels
    take in up to 3 voxels in front of it, ``object_front``) keeps the full
    field's density exactly either way."""
    from mi_voldis.field.state import density_of
    voxel, centre, radius = 2.0 / 39, np.array([0.0, FLOOR_Y + 0.3, 0.0]), 0.3
    kept = {}
    for gap in (0, 4):
        ds, full, inputs, state = guided_removal(tmp_path / str(gap), keep_seen=True, keep_seen_gap=gap)
        pts, real = vertex_positions(full)
        r = np.linalg.norm(pts - centre, axis=1)
        above = real & (pts[:, 1] > FLOOR_Y + 2.5 * voxel) & sphere_seen_unmasked(ds, pts, voxel, centre, grow=3)
        haze, beyond = above & (r >= radius) & (r < radius + 2.5 * voxel), above & (r > radius + 8 * voxel)
        bg, fu = density_of(state.fields["bg"]), density_of(full)
        assert haze.sum() > 50 and beyond.sum() > 1000
        assert np.array_equal(bg[beyond], fu[beyond])
        kept[gap] = np.logaddexp(0, bg[haze]).mean() / np.logaddexp(0, fu[haze]).mean()  # softplus density
    assert kept[0] == pytest.approx(1.0) and kept[4] < 0.5, kept


def object_cells(tmp_path, **settings):
    from mi_voldis.fit.background import background_regions
    ds, cfg, full, FitInputs, FitState, Adam = synthetic_object_scene()
    cfg = cfg.replace(**settings)
    state = FitState(np.array([-1.0] * 3), np.array([1.0] * 3), Adam({}, 0.9, 0.99), fields={"full": full})
    inputs = FitInputs.of(ds, cfg, str(tmp_path / "state.npz"), False)
    hull, _, obj, _ = background_regions(inputs, state)
    pts, real = vertex_positions(full)
    return ds, cfg, np.array(hull) > 0, np.array(obj), pts, real


def sphere_chords(ds, pts, centre, radius=0.3, erode=2):
    """Per masked training view (rows) and point: the length of the way from the camera to the point
    inside the sphere (0 where it misses, inf where the point is out of the view's frame), and whether
    the point lies inside the view's mask eroded by ``erode`` pixels."""
    chords, inside = [], []
    for v in ds.masked_train:
        cam = ds.cameras[v]
        px, py, z = project(cam, pts)
        o = cam.to_world[:3, 3]
        dist = np.linalg.norm(pts - o, axis=1)
        d = (pts - o) / dist[:, None]
        b = np.sum((o - centre) * d, axis=1)
        disc = b * b - (np.sum((o - centre) ** 2) - radius ** 2)
        root = np.sqrt(np.maximum(disc, 0.0))
        chord = np.clip(np.minimum(-b + root, dist) - np.maximum(-b - root, 0.0), 0.0, None) * (disc > 0)
        ix, iy = np.floor(px).astype(int), np.floor(py).astype(int)
        framed = (z > 0) & (ix >= 0) & (ix < cam.width) & (iy >= 0) & (iy < cam.height)
        core = ds.masks[v] & ~dilate(~ds.masks[v], erode)
        chords.append(np.where(framed, chord, np.inf))
        inside.append(framed & core[np.clip(iy, 0, cam.height - 1), np.clip(ix, 0, cam.width - 1)])
    return np.array(chords), np.array(inside)


def test_the_objects_cells_are_the_dense_hull_cells_masked_rays_show_and_no_view_sees_unmasked(tmp_path):
    """On the opaque sphere standing on the floor, with ``object_alpha`` low enough to take in a soft
    edge: no view sees an object cell unmasked (analytically: outside the view's mask grown by a pixel,
    the ray to the cell not through the sphere); the sphere's skin that a masked view looks at (away
    from the mask's edge) is object, though the floor's cells beside it are as opaque; what the sphere
    hides from every view (its core, the floor under it: each ray to them crosses two voxels of it or
    more) is not, as the background continues there; the sphere's haze is no part. The full field's
    median depth decides what a view sees: the haze in front of the floor beside the sphere does not
    hide it."""
    ds, cfg, hull, obj, pts, real = object_cells(tmp_path, object_front=False, hole_carve=False)
    assert cfg.object_alpha <= 0.2
    voxel = 2.0 / 39
    centre = np.array([0.0, FLOOR_Y + 0.3, 0.0])
    r = np.linalg.norm(pts - centre, axis=1)
    seen = sphere_seen_unmasked(ds, pts, voxel, centre)
    assert not (obj & seen).any()
    shifts = [np.zeros(3)] + [s * voxel * e for e in np.eye(3) for s in (-1, 1)]
    hidden = np.all([(sphere_chords(ds, pts + s, centre)[0] >= 2 * voxel).all(axis=0) for s in shifts], axis=0)
    surface = real & hull & (pts[:, 1] > FLOOR_Y + 0.5 * voxel) & (pts[:, 1] < FLOOR_Y + 1.5 * voxel)
    assert (surface & hidden).sum() > 10
    assert not obj[surface & hidden].any()
    assert not obj[real & (r < 0.3 - 3 * voxel)].any()
    outward = pts + voxel * (pts - centre) / np.maximum(r, 1e-9)[:, None]
    chords, inside = sphere_chords(ds, outward, centre)
    skin = real & (r < 0.3) & (r > 0.3 - 0.5 * voxel) & ((chords == 0) & inside).any(axis=0)
    assert skin.sum() > 50
    assert obj[skin].all()
    assert not obj[real & (r > 0.3 + 0.5 * voxel) & (pts[:, 1] > FLOOR_Y + 2 * voxel)].any()


def test_the_cells_before_the_object_on_masked_rays_join_it_where_no_view_sees_them(tmp_path):
    """With ``object_front`` the object's cells are those of the dense rule and, in addition, hull cells
    in front of the sphere: each lies within a cell's diagonal of a masked ray's way from the camera to
    the sphere (a corner of a cell it samples) and no view sees it unmasked, and none is inside the
    sphere (the dense rule has those)."""
    ds, _, hull, obj, pts, real = object_cells(tmp_path, object_front=True, hole_carve=False)
    _, _, _, dense, _, _ = object_cells(tmp_path, object_front=False, hole_carve=False)
    voxel = 2.0 / 39
    centre = np.array([0.0, FLOOR_Y + 0.3, 0.0])
    assert (obj >= dense).all()
    added = obj & ~dense
    assert added.sum() > 20
    assert not (added & sphere_seen_unmasked(ds, pts, voxel, centre)).any()
    assert not (added & ~hull).any()
    near = np.full(added.sum(), np.inf)  # distance to the nearest masked ray before the sphere
    for v in ds.masked_train:
        cam = ds.cameras[v]
        py, px = np.nonzero(ds.masks[v])
        o, d = pixel_rays(cam, px + 0.5, py + 0.5)
        end = sphere_hit(o, d, centre, 0.3)
        rel = pts[added][:, None, :] - o[None]
        t = np.clip(np.einsum("pri,ri->pr", rel, d), 0, end[None])
        near = np.minimum(near, np.linalg.norm(rel - t[..., None] * d[None], axis=-1).min(axis=1))
    assert (near <= np.sqrt(3) * voxel).all()  # a corner of a cell some such ray samples
    assert (np.linalg.norm(pts[added] - centre, axis=1) >= 0.3 - voxel).all()  # in front, not inside


def test_hole_carving_adds_the_unseen_space_before_the_floor_and_nothing_on_or_under_it(tmp_path):
    """With ``hole_carve`` the object's cells are those without it and, in addition, unseen hull cells
    the masked views vote in front of the floor the sphere hides (the sphere's haze shell among them:
    above the floor, some view's masked ray passes through it before the floor) or far below it; no
    floor cell, none within the shell under it, and none that a view sees unmasked joins."""
    ds, _, hull, obj, pts, real = object_cells(tmp_path, hole_carve=True)
    _, _, _, without, _, _ = object_cells(tmp_path, hole_carve=False)
    voxel = 2.0 / 39
    centre = np.array([0.0, FLOOR_Y + 0.3, 0.0])
    r = np.linalg.norm(pts - centre, axis=1)
    assert (obj >= without).all()
    added = obj & ~without
    assert added.sum() > 20
    assert not (added & ~hull).any()
    above = pts[:, 1] > FLOOR_Y  # (the analytic visibility knows the sphere alone: under the floor it says nothing)
    assert not (added & above & sphere_seen_unmasked(ds, pts, voxel, centre)).any()
    assert not added[np.abs(pts[:, 1] - FLOOR_Y) < 1.5 * voxel].any()  # the floor and the shell about it stay
    assert added[pts[:, 1] < FLOOR_Y - 0.3].any()  # far under the floor, where the hull reaches
    shell = real & hull & (r > 0.3 + 0.5 * voxel) & (r < 0.3 + 2.5 * voxel) & (pts[:, 1] > FLOOR_Y + 3 * voxel)
    shell &= ~sphere_seen_unmasked(ds, pts, voxel, centre)
    assert shell.sum() > 20 and obj[shell].mean() > 0.9


def test_the_cells_voted_at_or_under_the_hidden_floor_are_the_floors_and_what_lies_under_it(tmp_path):
    """``object_behind_fill`` gives back to the fill the object's cells that the masked views vote at or
    behind the surface the object hides (:func:`behind_hidden_surface`). Asked of every hull cell of the
    sphere on the floor: some are voted so, every one lies within a voxel and a half of the floor or under
    it, and nearly all the hull's cells under the floor below the sphere are; none of the sphere above it."""
    from mi_voldis.fit.background import behind_hidden_surface
    from mi_voldis.fit.lift import training_depths
    ds, cfg, full, FitInputs, FitState, Adam = synthetic_object_scene()
    state = FitState(np.array([-1.0] * 3), np.array([1.0] * 3), Adam({}, 0.9, 0.99), fields={"full": full})
    inputs = FitInputs.of(ds, cfg, str(tmp_path / "state.npz"), False)
    hull = object_cells(tmp_path)[2]
    got = np.array(behind_hidden_surface(inputs, full, mi.Bool(hull), training_depths(inputs, state, median=True)))
    pts, real = vertex_positions(full)
    voxel = 2.0 / 39
    assert got.sum() > 0 and not (got & ~hull).any()
    assert (pts[got, 1] < FLOOR_Y + 1.5 * voxel).all()
    under = real & hull & (pts[:, 1] < FLOOR_Y - 1.5 * voxel) & (np.hypot(pts[:, 0], pts[:, 2]) < 0.15)
    assert under.sum() > 10 and got[under].mean() > 0.9
    sphere = np.linalg.norm(pts - np.array([0.0, FLOOR_Y + 0.3, 0.0]), axis=1) < 0.3
    assert not got[sphere & (pts[:, 1] > FLOOR_Y + 1.5 * voxel)].any()
    # within two voxels of the candidates' lowest heights alone (the up is +y here: level cameras)
    low = np.array(behind_hidden_surface(inputs, full, mi.Bool(hull), training_depths(inputs, state, median=True),
                                         layers=2.0))
    bottom = np.percentile(pts[real & hull, 1], 1)
    assert low.sum() > 0 and not (low & ~got).any()
    np.testing.assert_array_equal(low, got & (pts[:, 1] < bottom + 2 * voxel))


def test_the_fill_takes_back_exactly_the_objects_cells_voted_at_or_under_the_hidden_floor(tmp_path):
    """With ``object_behind_fill`` (the default, over all the object's cells here) the object's cells are
    those without it less what :func:`behind_hidden_surface` votes at or under the floor among them."""
    from mi_voldis.fit.background import behind_hidden_surface
    from mi_voldis.fit.lift import training_depths
    on = object_cells(tmp_path / "on", hole_carve=False, object_behind_layers=0.0)[3]
    off = object_cells(tmp_path / "off", hole_carve=False, object_behind_fill=False)[3]
    ds, cfg, full, FitInputs, FitState, Adam = synthetic_object_scene()
    state = FitState(np.array([-1.0] * 3), np.array([1.0] * 3), Adam({}, 0.9, 0.99), fields={"full": full})
    inputs = FitInputs.of(ds, cfg, str(tmp_path / "state.npz"), False)
    behind = np.array(behind_hidden_surface(inputs, full, mi.Bool(off), training_depths(inputs, state, median=True)))
    np.testing.assert_array_equal(on, off & ~behind)


def test_the_inpainting_hole_takes_in_occluders_in_front_of_the_object_only():
    """Around a mask whose object stands at depth 2 in front of a wall at 5, a post at depth 1 touching
    the mask joins the hole (within the ring), the wall does not, nor the post beyond the ring."""
    from mi_voldis.fit.guide import inpainting_hole
    h, w = 40, 60
    depth = np.full((h, w), 5.0)
    region = np.zeros((h, w), bool)
    region[15:25, 25:35] = True
    depth[region] = 2.0
    depth[:, 20:25] = 1.0  # the post, left of the mask, every row
    hit = np.ones((h, w), bool)
    hole = inpainting_hole(region, depth, hit, region, ring=4)
    assert hole[region].all()
    assert hole[15:25, 21:25].all()  # the post beside the mask
    assert not hole[:10, 20:25].any()  # the post far above it: beyond the ring
    assert not (hole & (depth == 5.0)).any()  # the wall stays a source
    assert (inpainting_hole(region, depth, np.zeros((h, w), bool), region, 4) == region).all()  # no surfaces


def test_the_colour_prior_continues_the_wall_behind_not_the_occluder():
    """The prior's 2D fill inside the mask shows the wall's colour, not the post's beside it."""
    from mi_voldis.fit.guide import inpainting_hole
    h, w = 40, 60
    image = np.full((h, w, 3), [0.5, 0.5, 0.5], np.float32)
    depth = np.full((h, w), 5.0)
    region = np.zeros((h, w), bool)
    region[15:25, 25:35] = True
    image[region], depth[region] = [0.9, 0.1, 0.1], 2.0
    image[:, 18:25], depth[:, 18:25] = [0.1, 0.8, 0.1], 1.0  # a green post in front
    telea = inpainter("telea")
    plain = telea(image, region)[region]
    aware = telea(image, inpainting_hole(region, depth, np.ones((h, w), bool), region, ring=8))[region]
    grey = np.array([0.5, 0.5, 0.5])
    assert np.abs(aware - grey).max() < 0.03
    assert np.abs(plain - grey).max() > 0.15  # without it the post bleeds in


def test_the_guided_prior_targets_each_views_own_inpainting_inside_its_mask_only(tmp_path):
    """The prior's rays are exactly the grown masks' pixels of the masked training views (a view without
    a mask gives none) and their effect masks' (here the sphere's dark fringe), their colours each view's
    2D inpainting there; the refit with it changes
    nothing the views see outside the masks by more than 2/255 beyond what the harmonic refit changes."""
    from mi_voldis.fit.fields import fit_integrator
    from mi_voldis.fit.guide import colour_prior
    from mi_voldis.fit.train import fit
    ds, cfg, full, FitInputs, FitState, Adam = synthetic_object_scene(empty=-7.0)
    ds.masked = np.ones(len(ds.images), bool)
    unmasked = int(ds.train[-1])
    ds.masked[unmasked], ds.masks[unmasked] = False, True  # a view without a mask: all True, not used
    renders = {}
    for strategy in ("harmonic", "guided"):
        run_cfg = cfg.replace(bg_strategy=strategy, steps_bg=30)
        adam = Adam({}, run_cfg.adam_beta1, run_cfg.adam_beta2)
        state = FitState(np.array([-1.0] * 3), np.array([1.0] * 3), adam, fields={"full": full})
        state.schedule, state.steps_full = [[0, 40]], 1
        checkpoint = str(tmp_path / f"{strategy}.npz")
        state.save(checkpoint, "bg", 0)
        inputs, state = fit(ds, checkpoint, run_cfg, resume=True, progress=False)
        assert ("psnr_prior" in state.log[-1]) == (strategy == "guided")
        integ = fit_integrator(inputs, state)
        renders[strategy] = {v: render_camera(integ, ds.cameras[v], ("bg",))["bg"][0] for v in ds.test}
    bank, pool = colour_prior(inputs, state, "telea")
    grow = int(np.ceil(0.01 * np.hypot(*ds.size)))
    effects = inputs.ds.effects if inputs.ds.effects is not None else np.zeros(ds.masks.shape, bool)
    expected = np.stack([dilate(ds.masks[v], grow) | effects[v] if v != unmasked else np.zeros(ds.size, bool)
                         for v in ds.train])
    np.testing.assert_array_equal(np.sort(pool), np.flatnonzero(expected.reshape(-1)))
    every, centres = np.arange(bank.pixels, dtype=np.uint32), np.zeros((bank.pixels, 2), np.float32)
    colours = np.array(bank.rays(every, centres)[2]).T.reshape(len(ds.train), *ds.size, 3)
    for k, v in enumerate(ds.train):
        if v == unmasked:
            continue
        painted = inpainter("telea")(ds.images[v], expected[k])  # no occluder in this scene
        # the bank keeps 10-bit codes (raybank): within half their step of the painting, and of the photographs
        # (as the painting rounded them to 8 bits)
        tenbit = 0.5 / 1023 + 1e-6
        np.testing.assert_allclose(colours[k][expected[k]], painted[expected[k]], rtol=0, atol=tenbit)
        outside = ~expected[k]
        np.testing.assert_allclose(colours[k][outside], ds.images[v][outside], rtol=0, atol=0.51 / 255 + tenbit)
    flat = colour_prior(inputs, state, lambda image, hole: np.where(hole[..., None], 0.25, image))[0]  # any callable
    flat_colours = np.array(flat.rays(every, centres)[2]).T
    np.testing.assert_allclose(flat_colours[pool], 0.25, rtol=0, atol=0.5 / 1023)
    for v in ds.test:
        out = ~dilate(ds.masks[v], int(np.ceil(cfg.hull_dilation * np.hypot(*ds.size))) + 2)
        assert np.abs(renders["guided"][v][out] - renders["harmonic"][v][out]).max() < 2 / 255


CONSISTENCY_CAMS = [Camera(look_at([0.0, 1.0, 1.8], [0.0, FLOOR_Y, 0.0]), 50.0, 64, 48),
                    Camera(look_at([0.4, 1.0, 1.7], [0.0, FLOOR_Y, 0.0]), 50.0, 64, 48)]
BALL = (np.array([0.2, -0.25, 0.5]), 0.22)  # between the second camera and the floor


def floor_and_ball(cam, ball=True):
    """Exact image and depth of a smoothly textured floor, with a flat red ball in front if ``ball``."""
    py, px = np.mgrid[0:cam.height, 0:cam.width]
    o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
    t = plane_depth(cam).ravel()
    p = o + t[:, None] * d
    rgb = np.stack([0.5 + 0.3 * np.sin(12 * p[:, 0]), 0.5 + 0.3 * np.cos(9 * p[:, 2]),
                    0.5 + 0.2 * np.sin(8 * p[:, 0] + 5 * p[:, 2])], -1)
    if ball:
        hit = sphere_hit(o, d, *BALL)
        rgb = np.where((hit < t)[:, None], [0.9, 0.1, 0.1], rgb)
        t = np.minimum(t, hit)
    return rgb.reshape(cam.height, cam.width, 3).astype(np.float32), t.reshape(cam.height, cam.width)


def test_consistency_of_a_textured_floor_is_high_with_its_true_depth_and_drops_with_a_wrong_one():
    """The removal metric samples each view's image through its nearest other view's depth: the exact
    images of a floor texture agree through the floor's depth (up to bilinear sampling), less through
    depths 3% too far in both views (within the z-test's tolerance, so scored)."""
    from types import SimpleNamespace

    from mi_voldis.tasks.removal import consistency
    ds = SimpleNamespace(cameras=CONSISTENCY_CAMS, masks=[np.ones((48, 64), bool)] * 2)
    scene = [floor_and_ball(c, ball=False) for c in CONSISTENCY_CAMS]
    images = {v: rgb for v, (rgb, _) in enumerate(scene)}
    depth = {v: t for v, (_, t) in enumerate(scene)}
    assert all(np.isfinite(t).all() for t in depth.values())
    exact = consistency(ds, [0, 1], images, depth, 0)
    wrong = consistency(ds, [0, 1], images, {v: 1.03 * t for v, t in depth.items()}, 0)
    assert exact > 40.0
    assert wrong < exact - 6.0


def test_the_consistency_warp_leaves_out_what_an_occluder_hides_in_either_view():
    """Reprojection with a z-test: view 1's floor that the ball hides from view 0 is left out (NaN),
    not scored against the ball; every pixel kept (the ball's too, where both views see the same point
    of it) matches the exact image up to bilinear sampling (RMS under 0.01); with no z-test (infinite
    tolerance) the ball's colour is scored against the floor; the shares sort what is left out."""
    from types import SimpleNamespace

    from mi_voldis.tasks.removal import NEARER, consistency_shares, depth_test, reproject
    (rgb0, t0), (rgb1, t1) = (floor_and_ball(c) for c in CONSISTENCY_CAMS)
    cam0, cam1 = CONSISTENCY_CAMS
    floor0, floor1 = plane_depth(cam0), plane_depth(cam1)
    hidden_in_1 = t1 < floor1 - 1e-6
    assert 0.05 < hidden_in_1.mean() < 0.5 and (t0 < floor0 - 1e-6).any()
    warped = reproject(rgb0, t0, cam0, cam1, t1)  # view 0 seen from camera 1
    valid = np.isfinite(warped).all(axis=-1)
    # the floor of view 1 that the ball hides from view 0: where the point's ray in view 0 hits the ball
    py, px = np.mgrid[0:48, 0:64]
    o, d = pixel_rays(cam1, px.ravel() + 0.5, py.ravel() + 0.5)
    p = o + floor1.reshape(-1, 1) * d
    to_p = p - cam0.to_world[:3, 3]
    dist = np.linalg.norm(to_p, axis=1)
    hidden_in_0 = (sphere_hit(np.broadcast_to(cam0.to_world[:3, 3], p.shape), to_p / dist[:, None], *BALL)
                   < dist).reshape(48, 64) & ~hidden_in_1
    assert hidden_in_0.sum() > 10 and not valid[hidden_in_0].any()
    assert valid.mean() > 0.5
    assert np.sqrt(np.mean((warped[valid] - rgb1[valid]) ** 2)) < 0.01  # 40 dB
    loose = reproject(rgb0, t0, cam0, cam1, t1, tolerance=np.inf)
    assert np.abs(loose[hidden_in_0] - rgb1[hidden_in_0]).max() > 0.3
    # the share the metric compares: both directions' kept pixels, over whole-frame masks
    ds = SimpleNamespace(cameras=CONSISTENCY_CAMS, masks=[np.ones((48, 64), bool)] * 2)
    back = np.isfinite(reproject(rgb1, t1, cam1, cam0, t0)).all(axis=-1)
    shares = consistency_shares(ds, [0, 1], {0: t0, 1: t1}, 0)
    assert shares["compared"] == pytest.approx((valid.mean() + back.mean()) / 2)
    assert sum(shares.values()) == pytest.approx(1.0)
    # view 1's floor behind the ball from view 0: nearer; view 1's ball, where view 0 sees the floor: farther
    code = depth_test(t0, cam0, cam1, t1)[2].reshape(48, 64)
    assert (code[hidden_in_0] == NEARER).all() and shares["nearer"] > 0 and shares["farther"] > 0


def test_the_removal_score_rates_the_foreground_matte_against_the_masks_on_a_capture(tmp_path):
    """The benchmark's removal score gives the foreground's IoU (coverage and EXR matte) against the
    exact coverage where there is ground truth, and against the masks on a capture without it (the
    same views, the same figures here: the synthetic scene's coverage is its masks); with ``keep_seen``
    and no gap (the haze, outside the masks, stays in the background) the sphere's foreground matches
    its masks."""
    import dataclasses

    from mi_voldis.bench.strategies import evaluate
    from mi_voldis.fit.fields import fit_integrator
    ds, _, inputs, state = guided_removal(tmp_path, keep_seen=True, keep_seen_gap=0)
    integ = fit_integrator(inputs, state)
    truth, _ = evaluate(dataclasses.replace(ds, coverage=ds.masks.astype(np.float32)), integ)
    capture, _ = evaluate(dataclasses.replace(ds, backgrounds=None), integ)
    assert capture["volume"]["psnr_mask"] is None and capture["volume"]["consistency_psnr"] is not None
    for key in ("fg_coverage_iou", "fg_matte_iou"):
        assert truth["volume"][key] > 0.8
        assert capture["volume"][key] == pytest.approx(truth["volume"][key], abs=1e-6)


def test_the_removal_is_scored_in_the_same_region_whatever_hull_the_fit_grew(tmp_path):
    """The removal score's region is the protocol's (masks dilated by SCORE_DILATION of the diagonal), not
    the fit's ``hull_dilation``: a fit that grows its hull is scored on the pixels the default is, and the
    2D inpainters beside it get the same masks (a larger one would lower their score and lift the margin)."""
    from mi_voldis.bench.strategies import evaluate
    from mi_voldis.fit.fields import fit_integrator
    from mi_voldis.metrics import psnr, score_dilation
    ds, _, inputs, state = guided_removal(tmp_path, hull_dilation=0.1)
    dil = score_dilation(ds.size)
    assert 0 < dil < np.ceil(0.1 * np.hypot(*ds.size))
    rows, renders = evaluate(ds, fit_integrator(inputs, state))
    region = {v: dilate(ds.masks[v], dil) for v in ds.test}
    expected = np.mean([psnr(np.clip(renders[v]["bg"][0], 0, 1), ds.backgrounds[v], region[v]) for v in ds.test])
    assert rows["volume"]["psnr_mask"] == pytest.approx(expected, abs=1e-9)
    telea = inpainter("telea")
    assert rows["telea"]["psnr_mask"] == pytest.approx(np.mean(
        [psnr(telea(ds.images[v], region[v]), ds.backgrounds[v], region[v]) for v in ds.test]), abs=1e-9)


def hidden_floor_without_its_brick(tmp_path, name, **settings):
    """The synthetic sphere's full field without the floor under it and without the brick there (no
    training ray ends behind an object, so a fit keeps none), and (dataset, full field, inputs, state) after
    the guided background's start (``steps_bg=0``) or refit with ``settings``."""
    from mi_voldis.field.state import resample
    from mi_voldis.fit.train import fit
    ds, cfg, full, FitInputs, FitState, Adam = synthetic_object_scene(hidden_floor=True)
    keep = full.layout.table > 0
    keep[2, 1, 2] = False  # (bz, by, bx): x, z in [-0.18, 0.18], y in [-0.59, -0.23]: the floor under the sphere
    full = resample(full, None, keep)
    cfg = cfg.replace(**{"bg_strategy": "guided", "steps_bg": 0, **settings})
    state = FitState(np.array([-1.0] * 3), np.array([1.0] * 3), Adam({}, cfg.adam_beta1, cfg.adam_beta2),
                     fields={"full": full})
    state.schedule, state.steps_full = [[0, 40]], 1
    state.save(str(tmp_path / f"{name}.npz"), "bg", 0)
    return (ds, full) + fit(ds, str(tmp_path / f"{name}.npz"), cfg, resume=True, progress=False)


def under_the_sphere(ds, integrator):
    """The background's opacity and its median depth's distance from the floor plane on the held-out
    pixels whose ray meets the floor under the sphere (within 0.15 of its axis) inside the mask."""
    from mi_voldis.render.surface import median_depth
    alphas, errors = [], []
    for v in ds.test:
        cam = ds.cameras[v]
        py, px = np.mgrid[0:cam.height, 0:cam.width]
        o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
        t = plane_depth(cam).reshape(-1)
        hit = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
        under = (np.abs(hit[:, 0]) < 0.15) & (np.abs(hit[:, 2]) < 0.15) & ds.masks[v].reshape(-1)
        alpha = render_camera(integrator, cam, ("bg",))["bg"][1].reshape(-1)
        depth, ends = median_depth(integrator, cam, layer="bg")
        alphas.append(alpha[under])
        errors.append(np.where(ends.reshape(-1), np.abs(depth.reshape(-1) - t), np.inf)[under])
    return np.concatenate(alphas), np.concatenate(errors)


def test_the_hull_is_stored_in_full_before_the_fill_and_the_full_fields_renders_stay(tmp_path):
    """:func:`allocate_hull` allocates again, of the bricks taken out of the field (the lower two layers:
    the floor and what lies under it), exactly those a corner of which the hull's rule puts in the visual
    hull (among them the floor's brick under the sphere, not the floor's far from it), and the full field
    renders as before, to the float rounding of the resampled vertices: the new bricks are empty."""
    import os

    from mi_voldis.field.state import resample
    from mi_voldis.fit.background import allocate_hull
    from mi_voldis.fit.fields import FitInputs
    ds, cfg, full, _, _, _ = synthetic_object_scene(hidden_floor=True)
    inputs = FitInputs.of(ds, cfg, os.devnull, progress=False)
    keep = full.layout.table > 0
    keep[:, :2, :] = False  # (bz, by, bx): y below -0.18
    holed = resample(full, None, keep)
    grown = allocate_hull(inputs, holed)
    assert ((grown.layout.table > 0) >= keep).all()
    added = (grown.layout.table > 0) & ~keep
    b, span = full.layout.brick, np.array(full.shape) - 1
    px = int(np.ceil(cfg.hull_dilation * np.hypot(*ds.size)))
    expected = np.zeros_like(added)
    for bz, by, bx in np.argwhere(~keep):
        corners = np.array([[min((bx + i) * b, span[0]), min((by + j) * b, span[1]), min((bz + k) * b, span[2])]
                            for i in (0, 1) for j in (0, 1) for k in (0, 1)]) / span
        scene = corners @ full.to_world[:3, :3].T + full.to_world[:3, 3]
        expected[bz, by, bx] = _reference_hull(scene, [ds.cameras[v] for v in ds.masked_train],
                                               dilate(ds.masks[ds.masked_train], px), cfg.hull_min_views).any()
    np.testing.assert_array_equal(added, expected)
    assert added[2, 1, 2] and not added[2, 1, 4] and 0 < added.sum() < (~keep).sum()
    assert allocate_hull(inputs, grown) is grown  # nothing left to allocate
    props = integrator_properties(SceneSpace("world"), samples=256, step_size=0.5 * 2.0 / 39)
    for v in ds.test:
        layers = [render_camera(build_integrator({"full": f.plugin(), "bg": f.plugin()}, props), ds.cameras[v],
                                ("full",))["full"] for f in (holed, grown)]
        np.testing.assert_allclose(layers[0][0], layers[1][0], rtol=0, atol=1e-5)  # rgb
        np.testing.assert_allclose(layers[0][1], layers[1][1], rtol=0, atol=1e-5)  # alpha


def test_the_hole_shows_a_surface_at_the_hidden_floor_even_where_the_fit_kept_no_bricks(tmp_path, monkeypatch):
    """With ``hole_carve`` the background starts the hidden floor opaque from the floor plane the masks'
    surroundings continue, so the held-out views see through the hole an opaque surface at the plane's
    depth (within two voxels). Without it the fill and the refit put the floor's density into the bricks
    :func:`allocate_hull` kept for it (after 60 steps an opacity there more than three times what it is
    with no room kept for it, the allocation skipped, where the hole stays all but transparent)."""
    from mi_voldis.fit import background
    from mi_voldis.fit.fields import fit_integrator
    ds, _, inputs, state = hidden_floor_without_its_brick(tmp_path, "carve", hole_carve=True)
    alpha, error = under_the_sphere(ds, fit_integrator(inputs, state))
    assert len(alpha) > 10
    assert np.median(alpha) > 0.95 and alpha.min() > 0.7 and np.median(error) < 2 * 2.0 / 39, \
        (np.median(alpha), alpha.min(), np.median(error))
    seen = {}
    for room in (True, False):
        if not room:
            monkeypatch.setattr(background, "allocate_hull", lambda inputs, field: field)
        ds, _, inputs, state = hidden_floor_without_its_brick(tmp_path, f"fill{room}", steps_bg=60)
        assert (state.fields["bg"].layout.table[2, 1, 2] > 0) == room
        seen[room] = under_the_sphere(ds, fit_integrator(inputs, state))
    assert np.median(seen[False][0]) < 0.15 and np.median(seen[True][0]) > 3 * np.median(seen[False][0]), \
        (np.median(seen[True][0]), np.median(seen[False][0]))


def _reference_hull(points, cameras, masks, min_fraction, depths=None, tol=0.05):
    """The visual hull's rule in NumPy, every view projecting every point (what the kernels must equal)."""
    from mi_voldis.cameras import pixel_of
    seen = np.zeros(len(points), int)
    inside = np.zeros(len(points), int)
    for k, (cam, mask) in enumerate(zip(cameras, masks)):
        ix, iy, ok = pixel_of(cam, points)
        hit = np.zeros(len(points), bool)
        hit[ok] = mask[iy[ok], ix[ok]]
        if depths is not None and depths[k] is not None:
            dist = np.linalg.norm(points - cam.to_world[:3, 3], axis=1)
            hidden = np.zeros(len(points), bool)
            hidden[ok] = depths[k][iy[ok], ix[ok]] < (1.0 - tol) * dist[ok]
            ok &= hit | ~hidden
        seen += ok
        inside += hit
    return (seen > 0) & (inside >= min_fraction * seen)


def test_the_hull_and_visibility_kernels_answer_as_numpy_does_view_by_view():
    """visual_hull, in_view and seen_elsewhere run each view as a Dr.Jit kernel over every point
    (DevicePoints): the same booleans and colours as NumPy's projection of every point into every view,
    on random views, disc masks and depth maps with holes (NaN), whatever the fraction."""
    from mi_voldis.cameras import Camera, look_at
    from mi_voldis.fit.hull import visual_hull
    from mi_voldis.fit.visibility import in_view, seen_elsewhere
    rng = np.random.default_rng(7)
    h, w = 30, 40
    cams, masks, depths = [], [], []
    for _ in range(9):
        direction = rng.normal(size=3)
        cams.append(Camera(look_at(3.0 * direction / np.linalg.norm(direction), rng.normal(0, 0.2, 3)), 50.0, w, h))
        y, x = np.mgrid[:h, :w]
        masks.append((x - rng.uniform(10, 30)) ** 2 + (y - rng.uniform(8, 22)) ** 2 < rng.uniform(20, 120))
        depth = rng.uniform(1.5, 4.0, (h, w))
        depth[rng.random((h, w)) < 0.1] = np.nan
        depths.append(depth)
    masks = np.array(masks)
    points = rng.uniform(-1.2, 1.2, (4000, 3))
    for fraction in (0.5, 0.9, 1.0):
        for given in (None, depths, [d if k % 3 else None for k, d in enumerate(depths)]):
            got = visual_hull(points, cams, masks, 0, fraction, given)
            assert np.array_equal(got, _reference_hull(points, cams, masks, fraction, given)), (fraction, given is None)
            assert got.any() and not got.all()
    expected_view = np.zeros(len(points), bool)
    expected_seen = np.zeros(len(points), bool)
    from mi_voldis.cameras import pixel_of
    for cam, depth, mask in zip(cams, depths, masks):
        ix, iy, ok = pixel_of(cam, points)
        ok[ok] &= ~mask[iy[ok], ix[ok]]
        dist = np.linalg.norm(points - cam.to_world[:3, 3], axis=1)
        view, near = ok.copy(), ok.copy()
        view[ok] &= ~(depth[iy[ok], ix[ok]] < 0.95 * dist[ok])
        near[ok] &= np.abs(depth[iy[ok], ix[ok]] - dist[ok]) <= 0.03 * dist[ok]
        expected_view |= view
        expected_seen |= near
    assert np.array_equal(in_view(points, cams, depths, masks), expected_view) and expected_view.any()
    assert np.array_equal(seen_elsewhere(points, cams, depths, masks), expected_seen) and expected_seen.any()
    images = [rng.random((h, w, 3)) for _ in cams]
    seen, colour = seen_elsewhere(points, cams, depths, masks, images)
    assert np.array_equal(seen, expected_seen) and np.isnan(colour[~seen]).all()
    total, count = np.zeros((len(points), 3)), np.zeros(len(points))
    for cam, depth, mask, image in zip(cams, depths, masks, images):  # the mean colour of the views that see it
        ix, iy, ok = pixel_of(cam, points)
        ok[ok] &= ~mask[iy[ok], ix[ok]]
        dist = np.linalg.norm(points - cam.to_world[:3, 3], axis=1)
        ok[ok] &= np.abs(depth[iy[ok], ix[ok]] - dist[ok]) <= 0.03 * dist[ok]
        total[ok] += image[iy[ok], ix[ok]]
        count[ok] += 1
    np.testing.assert_allclose(colour[seen], total[seen] / count[seen, None], rtol=1e-12)
    assert len(visual_hull(points[:0], cams, masks, 0, 0.9)) == 0 == len(in_view(points[:0], cams, depths, masks))
    assert [a.shape for a in seen_elsewhere(points[:0], cams, depths, masks, images)] == [(0,), (0, 3)]


def test_fitting_keeps_the_bricks_where_training_rays_end():
    """The carve's evidence (:func:`~mi_voldis.fit.fields.ray_weights`) and rule, on the sphere on the
    floor: the bricks under the floor (behind its three vertices of raw 4, 98% opaque a voxel) and the
    empty space above the sphere get no weight from any training ray (every ray ends on the floor or the
    sphere); bricks of the floor the views see get a sample of most of a ray's light; and
    :func:`~mi_voldis.fit.fields.refine` keeps exactly the bricks above ``carve_weight``, grown by one, for
    two thresholds."""
    from mi_voldis.field.state import carve, shape_for
    from mi_voldis.fit.fields import fit_integrator, ray_weights, refine
    ds, cfg, full, FitInputs, FitState, Adam = synthetic_object_scene()
    lo, hi = np.array([-1.0] * 3), np.array([1.0] * 3)
    kept = {}
    for threshold in (1e-2, 0.3):
        cfg = cfg.replace(carve_weight=threshold)
        inputs = FitInputs.of(ds, cfg, "", progress=False)
        state = FitState(lo, hi, Adam({}, cfg.adam_beta1, cfg.adam_beta2), fields={"full": full})
        state.schedule, state.steps_full = [[0, 40]], 1
        integrator = fit_integrator(inputs, state)
        weights, evaluated = ray_weights(inputs, integrator, "full")
        assert weights.shape == full.layout.table.shape and len(evaluated) > 0
        b = full.layout.brick  # brick k holds the vertices k b .. k b + b - 1, a sample its nearest vertex's
        floor = int(np.floor((FLOOR_Y - lo[1]) / (2.0 / 39) + 0.5)) // b
        assert weights[:, :floor, :].max() < 1e-6  # under the floor
        top = int(np.floor((0.6 - lo[1]) / (2.0 / 39) + 0.5)) // b + 1  # bricks above y = 0.6: the sphere's
        assert weights[:, top:, :].max() < 1e-6  # top is at y = 0.1, its haze within 0.15 of it
        assert np.sort(weights[:, floor, :].ravel())[-20:].min() > 0.5
        refined = FitState(lo, hi, state.adam, fields={"full": full})
        used, _, weight = refine(inputs, refined, integrator, ("full",), 40)
        assert weight == threshold
        assert used == 40 and refined.fields["full"].layout.shape == shape_for(lo, hi, 40)
        expected = carve(full, weights > threshold)
        np.testing.assert_array_equal(refined.fields["full"].layout.table > 0, expected)
        kept[threshold] = expected.sum()
    assert kept[0.3] < kept[1e-2]


def test_a_stage_that_memory_binds_tightens_its_carve_only_as_far_as_it_must():
    """:func:`~mi_voldis.fit.fields.refine` under a vertex bound, on the sphere on the floor refined from
    40 to 72: without a bound, or where ``carve_weight``'s carve fits, it carves at ``carve_weight``;
    where that carve would hold the lattice below 72, it takes the loosest weight of
    :func:`~mi_voldis.fit.fields.carve_ladder` whose carve reaches 72 (exactly that carve's vertices);
    where none does, the loosest of those that reach the finest lattice any reaches, as a memory cap;
    with ``carve_weight_memory`` at ``carve_weight`` it never tightens."""
    from mi_voldis.field.state import carve, resampled_vertices, shape_for
    from mi_voldis.fit.fields import FitInputs, carve_ladder, fit_integrator, ray_weights, refine
    ds, cfg, full, _, FitState, Adam = synthetic_object_scene()
    lo, hi = np.array([-1.0] * 3), np.array([1.0] * 3)
    cfg = cfg.replace(carve_weight=1e-2, carve_weight_memory=0.3)
    ladder = carve_ladder(cfg)
    np.testing.assert_allclose(ladder, [1e-2, 1e-2 * 30 ** (1 / 3), 1e-2 * 30 ** (2 / 3), 0.3])
    assert carve_ladder(cfg.replace(carve_weight_memory=1e-2)) == [1e-2] == \
        carve_ladder(cfg.replace(carve_weight_memory=1e-3))
    inputs = FitInputs.of(ds, cfg, "", progress=False)

    def fresh():
        state = FitState(lo, hi, Adam({}, cfg.adam_beta1, cfg.adam_beta2), fields={"full": full})
        state.schedule, state.steps_full = [[0, 40]], 1
        return state

    integrator = fit_integrator(inputs, fresh())
    weights, _ = ray_weights(inputs, integrator, "full")
    keeps = [carve(full, weights > w) for w in ladder]

    def vertices(res):
        return [resampled_vertices(full, shape_for(lo, hi, res), keep) for keep in keeps]

    counts = vertices(72)
    assert all(a >= b for a, b in zip(counts, counts[1:]))
    k = next(i for i in range(1, len(ladder)) if counts[i] < counts[0])  # the first rung that keeps fewer

    def refined(bound, settings=inputs):
        state = fresh()
        got = refine(settings, state, integrator, ("full",), 72, bound)
        return got, state.fields["full"]

    assert refined(None)[0] == (72, None, 1e-2) == refined(counts[0])[0]  # no bound, or 1e-2's carve fits
    (used, why, weight), field = refined(counts[k])  # only rung k's carve (or a tighter one's) fits
    assert (used, why, weight) == (72, None, ladder[k]) and field.layout.shape == shape_for(lo, hi, 72)
    assert field.vertices == counts[k]
    at_56 = vertices(56)
    assert counts[-1] > at_56[-1] and at_56[0] > at_56[-1]
    j = next(i for i in range(len(ladder)) if at_56[i] <= at_56[-1])  # the loosest carve that reaches 56
    (used, why, weight), field = refined(at_56[-1])  # no carve reaches 72: 56, at rung j
    assert (used, why, weight) == (56, "memory", ladder[j]) and field.vertices == at_56[j]
    never = FitInputs.of(ds, cfg.replace(carve_weight_memory=1e-2), "", progress=False)
    (used, why, weight), _ = refined(counts[k], never)  # never tightens: held below 72
    assert used < 72 and (why, weight) == ("memory", 1e-2)
