"""Where rays end (mi_voldis.render.surface): the median depth of a wall, and the weight a slab of fog
in front of it takes, against the Beer-Lambert values."""
import mitsuba as mi
import numpy as np
import pytest

import mi_voldis  # noqa: F401
from mi_voldis.cameras import Camera, pixel_rays
from mi_voldis.device import from_numpy
from mi_voldis.field_state import new_field, vertex_positions
from mi_voldis.render.surface import front_weight, median_depth
from mi_voldis.scene import build_integrator, integrator_properties
from mi_voldis.space import SceneSpace
from mi_voldis.synth.rigs import look_at

RES = 41
VOXEL = 2.0 / (RES - 1)
WALL_Z, FOG_END = 0.5, -0.3  # the wall's front face; the fog fills z <= FOG_END from the box's face z = -1
SIGMA = 0.8  # the fog's extinction, per unit length: 43% opaque, so the median point is the wall's


def wall_behind_fog(sigma_fog):
    """A field over [-1, 1]^3: an opaque wall at z >= WALL_Z and fog of extinction ``sigma_fog`` at
    z <= FOG_END; a camera on the -z side looking at the wall through the fog."""
    lo, hi = -np.ones(3), np.ones(3)
    field = new_field(lo, hi, RES, 0, -20.0, 1.0 / VOXEL)
    pts, real = vertex_positions(field)
    values = np.array(field.data).reshape(-1, field.width)
    block = values[: field.layout.vertices_per_brick].copy()
    sigma = np.where(pts[:, 2] >= WALL_Z, 200.0, np.where(pts[:, 2] <= FOG_END, sigma_fog, 0.0)) * VOXEL  # / scale
    raw = np.where(sigma > 0, np.log(np.expm1(np.maximum(sigma, 1e-12))), -20.0)  # softplus(raw) = sigma / scale
    values[:, 0] = np.where(real, raw, -20.0)
    values[: field.layout.vertices_per_brick] = block
    field.data = from_numpy(mi.Float, values.ravel())
    props = integrator_properties(SceneSpace("world"), samples=512, step_size=0.25 * VOXEL)
    integrator = build_integrator({"full": field.plugin(), "bg": field.plugin()}, props)
    camera = Camera(look_at([0.0, 0.0, -3.0], [0.0, 0.0, 0.0]), 20.0, 24, 18)
    return integrator, camera


@pytest.mark.parametrize("sigma_fog", [0.0, SIGMA])
def test_the_median_depth_is_the_wall_and_the_fog_in_front_weighs_as_beer_lambert(sigma_fog):
    integrator, camera = wall_behind_fog(sigma_fog)
    py, px = np.mgrid[0:camera.height, 0:camera.width]
    _, d = pixel_rays(camera, px.ravel() + 0.5, py.ravel() + 0.5)
    cos = d[:, 2].reshape(camera.height, camera.width)  # the rays' slant through the z slabs
    depth, hit = median_depth(integrator, camera)
    assert hit.all()
    # the wall's density ramps up across the voxel in front of WALL_Z (trilinear): T = 1/2 there, to
    # within a sample step (a quarter voxel)
    z = depth * cos - 3.0
    assert (z > WALL_Z - 1.25 * VOXEL).all() and (z < WALL_Z + 0.25 * VOXEL).all(), (z.min(), z.max())
    front, hit = front_weight(integrator, camera, margin=0.1)
    assert hit.all()
    # the fog spans z in [-1, FOG_END] and up to one voxel beyond (the density ramps to zero there)
    shortest = 1.0 - np.exp(-sigma_fog * (FOG_END + 1.0) / cos)
    longest = 1.0 - np.exp(-sigma_fog * (FOG_END + 1.0 + VOXEL) / cos)
    assert (front >= shortest - 2e-3).all() and (front <= longest + 2e-3).all(), (front.min(), front.max())
    if sigma_fog == 0.0:
        assert front.max() < 1e-3
    else:
        assert front.mean() > 0.4  # about 1 - exp(-0.8 * 0.7) = 0.43
