"""The space the object masks prove empty (mi_voldis.fit.free_space): which vertices it takes, against the exact
geometry of a sphere seen from one side, and a fit that keeps them empty."""
import os

import numpy as np
import pytest

import mi_voldis  # noqa: F401
from mi_voldis.cameras import Camera, pixel_rays
from mi_voldis.field.state import new_field, vertex_positions
from mi_voldis.fit.free_space import distance_to, free_vertices, mask_gaps, nearest_filter
from mi_voldis.fit.hull import visual_hull
from mi_voldis.space import SceneSpace
from mi_voldis.synth.rigs import look_at

RADIUS = 0.3  # the object: a sphere at the origin
LATTICE = 61  # vertices every 0.05: a voxel spans about 3.5 pixels halfway from a camera to the sphere
# an arc on one side (-z), 100 degrees wide: the masks' cones meet about the sphere alone (a narrow rig's would
# run together towards the cameras, the whole tube in the hull)
CAMERAS = [[3.0 * np.sin(np.radians(a)), 0.0, -3.0 * np.cos(np.radians(a))] for a in (-50.0, -20.0, 20.0, 50.0)]


def sphere_hit(o, d, centre=(0.0, 0.0, 0.0)):
    """First distance along unit rays (o, d) to the sphere (about ``centre``), inf where they miss."""
    o = o - np.asarray(centre)
    b = np.sum(o * d, axis=1)
    disc = b * b - (np.sum(o * o, axis=1) - RADIUS ** 2)
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    return np.where((disc > 0) & (t > 0), t, np.inf)


# the object in two parts: spheres side by side across x, a notch between their discs in every view
TWINS = [(-0.33, 0.0, 0.0), (0.33, 0.0, 0.0)]


def twins_hit(o, d):
    return np.minimum(*(sphere_hit(o, d, c) for c in TWINS))


# a vertical pole (radius, axis through (x, z)) between camera 0 and the sphere, across the left of its image
POLE_RADIUS = 0.03
POLE = 0.5 * np.array(CAMERAS[0])[[0, 2]] + 0.1 * np.array([np.cos(np.radians(50.0)), np.sin(np.radians(50.0))])


def pole_hit(o, d):
    """First distance along unit rays (o, d) to the infinite vertical pole, inf where they miss."""
    oo, dd = o[:, [0, 2]] - POLE, d[:, [0, 2]]
    a = np.maximum(np.sum(dd * dd, axis=1), 1e-12)
    b = np.sum(oo * dd, axis=1)
    disc = b * b - a * (np.sum(oo * oo, axis=1) - POLE_RADIUS ** 2)
    t = (-b - np.sqrt(np.maximum(disc, 0.0))) / a
    return np.where((disc > 0) & (t > 0), t, np.inf)


def sphere_rig(pole=False, hit=sphere_hit):
    """The four cameras (128 x 96, wide: each frames the others' rays) and their masks of the sphere's visible
    pixels (with ``pole``: the pole hides part of it; ``hit``: another object's first distances)."""
    cams = [Camera(look_at(p, [0.0, 0.0, 0.0]), 70.0, 128, 96) for p in CAMERAS]
    masks = []
    for cam in cams:
        py, px = np.mgrid[0:cam.height, 0:cam.width]
        o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
        t = hit(o, d)
        seen = np.isfinite(t) & ~(pole_hit(o, d) < t) if pole else np.isfinite(t)
        masks.append(seen.reshape(cam.height, cam.width))
    return cams, np.stack(masks)


def lattice():
    return new_field(-1.5 * np.ones(3), 1.5 * np.ones(3), LATTICE, 0, -20.0, 1.0)


def surfaces(*hits):
    """A ``gap_depth`` for free_vertices: the first of the analytic ``hits`` along each pixel's ray."""
    def depth(cam, pixels):
        o, d = pixel_rays(cam, pixels % cam.width + 0.5, pixels // cam.width + 0.5)
        return np.min([h(o, d) for h in hits], axis=0)
    return depth


def reaches_object(points, cams, hit):
    """Per point: some camera's ray through it meets the object (``hit``) farther on."""
    out = np.zeros(len(points), bool)
    for cam in cams:
        c = cam.to_world[:3, 3]
        d = (points - c) / np.linalg.norm(points - c, axis=1, keepdims=True)
        out |= hit(np.broadcast_to(c, d.shape), d) > np.linalg.norm(points - c, axis=1)
    return out



def test_the_free_space_lies_between_a_camera_and_the_object_and_never_in_the_hull_behind_it_or_beside_it():
    """Every free vertex: outside the visual hull, and some camera's ray through it meets the sphere farther
    on; the point halfway from the first camera to the sphere is free, the point as far behind the sphere
    on that camera's axis (inside its mask, behind the object) and one above the sphere outside every
    mask are not."""
    cams, masks = sphere_rig()
    field = lattice()
    space = SceneSpace("world")
    free = free_vertices(field, space, cams, masks, 0, 0.9, 0.02)
    pts, real = vertex_positions(field)
    assert free.sum() > 20 and not free[~real].any()
    hull = visual_hull(pts[free], cams, masks, 0, 0.9)
    assert not hull.any()
    assert reaches_object(pts[free], cams, sphere_hit).all()

    def vertex(x, y, z):
        return int(np.argmin(np.linalg.norm(np.where(real[:, None], pts, np.inf) - [x, y, z], axis=1)))
    c0 = np.array(CAMERAS[0])
    assert free[vertex(*(0.5 * c0))]
    assert not free[vertex(*(-0.5 * c0))]
    assert not free[vertex(0.0, 1.2, 0.0)]


@pytest.mark.parametrize("told", [False, True])
def test_a_thin_occluder_in_front_of_the_object_keeps_every_vertex_that_reaches_it(told):
    """A pole a voxel wide between camera 0 and the sphere: its gap in mask 0 is a few pixels wide, so the
    vertices about it project inside the mask though their cells draw the pole. None of the vertices whose
    eight cells reach the pole is free; the free space beside it stays. ``told``: the surfaces given, the pole
    before the hull (a fitted field's)."""
    cams, masks = sphere_rig(pole=True)
    field = lattice()
    depth = surfaces(pole_hit, sphere_hit) if told else None
    free = free_vertices(field, SceneSpace("world"), cams, masks, 0, 0.9, 0.02, depth)
    pts, real = vertex_positions(field)
    voxel = 3.0 / (LATTICE - 1)
    # a vertex's cells: the cube of half-side one voxel about it; it reaches the pole where the square's
    # nearest point to the axis lies within the radius
    nearest = np.clip(POLE, pts[:, [0, 2]] - voxel, pts[:, [0, 2]] + voxel)
    reaches = real & (np.linalg.norm(nearest - POLE, axis=1) <= POLE_RADIUS)
    assert reaches.sum() > 100
    assert not (free & reaches).any(), pts[free & reaches][:5]
    assert free.sum() > 20


def test_a_notch_between_the_object_s_parts_frees_the_space_before_it_once_the_surfaces_tell_it_from_an_occluder():
    """Two spheres side by side: a closing of each mask fills the notch between their discs, and the masks
    alone keep the vertices near it. Told that the notch's rays meet nothing, more vertices are free, and each
    is still outside the hull with some camera's ray through it meeting the object farther on."""
    cams, masks = sphere_rig(hit=twins_hit)
    field = lattice()
    pts, _ = vertex_positions(field)
    space = SceneSpace("world")
    alone = free_vertices(field, space, cams, masks, 0, 0.9, 0.02)
    told = free_vertices(field, space, cams, masks, 0, 0.9, 0.02, surfaces(twins_hit))
    assert mask_gaps(masks[1], 6).sum() > 20  # the notch, as free_vertices' closing sees it (views 1 and 2)
    assert not (alone & ~told).any() and told.sum() > alone.sum() + 20, (alone.sum(), told.sum())
    assert not visual_hull(pts[told], cams, masks, 0, 0.9).any()
    assert reaches_object(pts[told], cams, twins_hit).all()


def test_a_gap_is_a_narrow_strip_with_the_mask_on_both_sides_and_never_the_mask_s_outer_edge():
    """A rectangle cut by a strip 2 pixels wide (touching the image's edge on the left): the distances run
    from the strip; the rectangle alone, or cut by a strip wider than the closing, has no gap."""
    mask = np.zeros((12, 20), bool)
    mask[2:10, 0:18] = True
    cut = mask.copy()
    cut[:, 9:11] = False
    row = distance_to(mask_gaps(cut, 2))[5]
    assert row[9] == row[10] == 0 and row[8] == row[11] == 1 and row[0] == 9 and row[19] == 9
    alone = distance_to(mask_gaps(mask, 2))
    assert alone.shape == mask.shape and np.isinf(alone).all()
    wide = mask.copy()
    wide[:, 6:14] = False
    assert not mask_gaps(wide, 2).any()


def test_a_pixel_takes_the_nearest_distance_of_its_neighbours_within_the_radius():
    image = np.full((5, 7), np.inf)
    image[2, 3], image[0, 0] = 2.0, 5.0
    out = nearest_filter(image, 1)
    assert out[1, 2] == 2.0 and out[3, 4] == 2.0 and out[1, 1] == 5.0
    assert out[1, 0] == 5.0 and np.isinf(out[4, 0]) and np.isinf(out[2, 5])
    rng = np.random.default_rng(4)  # against the minimum taken pixel by pixel, on doubles a float would round
    image = np.where(rng.random((9, 11)) < 0.7, np.inf, 1.0 + rng.random((9, 11)) * 1e-9)
    for radius in (1, 3):
        want = [[image[max(y - radius, 0):y + radius + 1, max(x - radius, 0):x + radius + 1].min() for x in range(11)]
                for y in range(9)]
        np.testing.assert_array_equal(nearest_filter(image, radius), want)


@pytest.mark.parametrize("margin", [0.02, 0.2])
def test_a_wider_margin_frees_no_more(margin):
    cams, masks = sphere_rig()
    field = lattice()
    space = SceneSpace("world")
    base = free_vertices(field, space, cams, masks, 0, 0.9, 0.0)
    wider = free_vertices(field, space, cams, masks, 0, 0.9, margin)
    assert not (wider & ~base).any() and wider.sum() < base.sum()


def test_a_fit_with_free_space_ends_with_that_space_empty(tiny_dataset, tmp_path):
    """The tiny tabletop fitted with ``free_space``: its final full field holds the empty density at every
    vertex the masks prove free on its lattice, and the setting is recorded."""
    import json

    from conftest import TINY_FIT

    from mi_voldis.data import load_dataset
    from mi_voldis.field.bricks import EMPTY_DENSITY
    from mi_voldis.field.state import density_of
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.fields import FitInputs
    from mi_voldis.fit.free_space import training_free_space
    from mi_voldis.fit.run import run_fit
    from mi_voldis.fit.state import FitState
    from mi_voldis.optim.adam import Adam
    run = str(tmp_path / "run")
    cfg = FitConfig.from_sources(None, TINY_FIT + ["free_space=true"])
    run_fit(tiny_dataset, run, cfg, progress=False, keep_checkpoints=True)
    with open(os.path.join(run, "config.json")) as f:
        assert json.load(f)["free_space"] is True
    state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, 0.9, 0.99))
    ds = load_dataset(tiny_dataset)
    inputs = FitInputs.of(ds, cfg, os.devnull, progress=False)
    # the last stage's, told by the fitted field: at least what the masks alone free
    kept = np.zeros(state.fields["full"].vertices, bool)
    kept[state.free] = True
    free = training_free_space(inputs, state.fields["full"])
    # the tiny lattice's voxels span many pixels, so only a few vertices lie a reach away from the masks' gaps
    assert free is not None and free.sum() > 0 and not (free & ~kept).any()
    assert np.abs(density_of(state.fields["full"])[kept] - EMPTY_DENSITY).max() < 1e-4


@pytest.mark.parametrize("sigma_fog", [0.0, 0.8])
def test_a_fitted_field_tells_a_gap_s_surface_where_its_opacity_reaches_a_quarter(sigma_fog):
    """field_gap_depth on a wall behind a slab of fog (tests/test_surface.py): with fog of extinction 0.8 its
    rays gather an opacity of 1/4 inside the fog, at z + 1 = ln(4/3) cos / 0.8 (Beer-Lambert, to a sample
    step); without fog, at the wall's face (its density ramps up over the voxel in front)."""
    from test_surface import VOXEL, WALL_Z, wall_behind_fog

    from mi_voldis.fit.free_space import OCCLUDER_OPACITY, field_gap_depth
    integrator, camera = wall_behind_fog(sigma_fog)
    pixels = np.arange(camera.width * camera.height)
    depth = field_gap_depth(integrator)(camera, pixels)
    o, d = pixel_rays(camera, pixels % camera.width + 0.5, pixels // camera.width + 0.5)
    z = o[:, 2] + depth * d[:, 2]
    if sigma_fog:
        want = -1.0 + np.log(1.0 / (1.0 - OCCLUDER_OPACITY)) * d[:, 2] / sigma_fog  # d_z: the ray's cosine
        assert np.abs(z - want).max() < 0.25 * VOXEL, (z.min(), z.max(), want.min())
    else:
        assert (z > WALL_Z - 1.25 * VOXEL).all() and (z < WALL_Z + 0.25 * VOXEL).all(), (z.min(), z.max())
