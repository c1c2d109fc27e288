"""The space the object masks prove empty (mi_voldis.fit.free_space): which vertices it takes, against the exact
geometry of a sphere seen from one side, and a fit that keeps them empty."""
import os

import numpy as np
import pytest

import mi_voldis  # noqa: F401
from mi_voldis.cameras import Camera, pixel_rays
from mi_voldis.field.state import new_field, vertex_positions
from mi_voldis.fit.free_space import free_vertices, nearest_filter
from mi_voldis.fit.hull import visual_hull
from mi_voldis.space import SceneSpace
from mi_voldis.synth.rigs import look_at

RADIUS = 0.3  # the object: a sphere at the origin
# an arc on one side (-z), 100 degrees wide: the masks' cones meet about the sphere alone (a narrow rig's would
# run together towards the cameras, the whole tube in the hull)
CAMERAS = [[3.0 * np.sin(np.radians(a)), 0.0, -3.0 * np.cos(np.radians(a))] for a in (-50.0, -20.0, 20.0, 50.0)]


def sphere_hit(o, d):
    """First distance along unit rays (o, d) to the sphere, inf where they miss."""
    b = np.sum(o * d, axis=1)
    disc = b * b - (np.sum(o * o, axis=1) - RADIUS ** 2)
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    return np.where((disc > 0) & (t > 0), t, np.inf)


def sphere_rig():
    cams = [Camera(look_at(p, [0.0, 0.0, 0.0]), 70.0, 64, 48) for p in CAMERAS]  # wide: each frames the others' rays
    masks = []
    for cam in cams:
        py, px = np.mgrid[0:cam.height, 0:cam.width]
        o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
        masks.append(np.isfinite(sphere_hit(o, d)).reshape(cam.height, cam.width))
    return cams, np.stack(masks)


def test_the_free_space_lies_between_a_camera_and_the_object_and_never_in_the_hull_behind_it_or_beside_it():
    """Every free vertex: outside the visual hull, and some camera's ray through it meets the sphere farther
    on; the point halfway from the first camera to the sphere is free, the point as far behind the sphere
    on that camera's axis (inside its mask, behind the object) and one above the sphere outside every
    mask are not."""
    cams, masks = sphere_rig()
    field = new_field(-1.5 * np.ones(3), 1.5 * np.ones(3), 31, 0, -20.0, 1.0)  # vertices every 0.1
    space = SceneSpace("world")
    free = free_vertices(field, space, cams, masks, 0, 0.9, 0.02)
    pts, real = vertex_positions(field)
    assert free.sum() > 20 and not free[~real].any()
    hull = visual_hull(pts[free], cams, masks, 0, 0.9)
    assert not hull.any()
    for p in pts[free]:
        reached = False
        for cam in cams:
            c = cam.to_world[:3, 3]
            d = (p - c) / np.linalg.norm(p - c)
            reached |= sphere_hit(c[None], d[None])[0] > np.linalg.norm(p - c)
        assert reached, p

    def vertex(x, y, z):
        return int(np.argmin(np.linalg.norm(np.where(real[:, None], pts, np.inf) - [x, y, z], axis=1)))
    c0 = np.array(CAMERAS[0])
    assert free[vertex(*(0.5 * c0))]
    assert not free[vertex(*(-0.5 * c0))]
    assert not free[vertex(0.0, 1.2, 0.0)]


def test_a_pixel_takes_the_nearest_distance_of_its_neighbours_within_the_radius():
    image = np.full((5, 7), np.inf)
    image[2, 3], image[0, 0] = 2.0, 5.0
    out = nearest_filter(image, 1)
    assert out[1, 2] == 2.0 and out[3, 4] == 2.0 and out[1, 1] == 5.0
    assert out[1, 0] == 5.0 and np.isinf(out[4, 0]) and np.isinf(out[2, 5])


@pytest.mark.parametrize("margin", [0.02, 0.2])
def test_a_wider_margin_frees_no_more(margin):
    cams, masks = sphere_rig()
    field = new_field(-1.5 * np.ones(3), 1.5 * np.ones(3), 31, 0, -20.0, 1.0)
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
    free = training_free_space(inputs, state.fields["full"])
    assert free is not None and free.sum() > 10
    assert np.abs(density_of(state.fields["full"])[free] - EMPTY_DENSITY).max() < 1e-4
