"""Where rays end (mi_voldis.render.surface): the median depth of a wall, and the weight a slab of fog
in front of it takes, against the Beer-Lambert values, in all and by band of distance from the wall."""
import mitsuba as mi
import numpy as np
import pytest

import mi_voldis  # noqa: F401
from mi_voldis.cameras import Camera, pixel_rays
from mi_voldis.device import from_numpy
from mi_voldis.field.state import new_field, vertex_positions
from mi_voldis.render.surface import front_weight, median_depth, weight_bands
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



@pytest.mark.parametrize("sigma_fog", [0.0, SIGMA])
def test_the_weight_by_band_of_distance_puts_the_wall_on_its_surface_and_the_fog_far_in_front(sigma_fog):
    """Bands of t / t_wall, t_wall the exact distance to the wall's face along each ray: the wall's weight
    (its density ramps up across the voxel in front of its face, a voxel = 1.4% of the distance) lies within
    2% of it; the fog's (z in [-1, FOG_END], at most 0.8 of the wall's distance) all below 0.9, as much as
    Beer-Lambert gives it; the bands sum to the ray's opacity. A pixel without a reference gets none."""
    integrator, camera = wall_behind_fog(sigma_fog)
    py, px = np.mgrid[0:camera.height, 0:camera.width]
    o, d = pixel_rays(camera, px.ravel() + 0.5, py.ravel() + 0.5)
    wall = ((WALL_Z - o[:, 2]) / d[:, 2]).reshape(camera.height, camera.width)
    reference = wall.copy()
    reference[0, 0] = np.nan
    bands = weight_bands(integrator, camera, reference, (0.9, 0.98, 1.02))
    assert bands.shape == (camera.height, camera.width, 4)
    assert np.all(bands[0, 0] == 0.0)
    rest = np.ones(wall.shape, bool)
    rest[0, 0] = False
    _, alpha, _ = render_full(integrator, camera)
    assert np.abs(bands.sum(-1)[rest] - alpha[rest]).max() < 1e-4
    cos = d[:, 2].reshape(camera.height, camera.width)
    fog = 1.0 - np.exp(-sigma_fog * (FOG_END + 1.0 + np.array([0.0, VOXEL]))[:, None, None] / cos)
    far = bands[..., 0][rest]
    assert (far >= fog[0][rest] - 2e-3).all() and (far <= fog[1][rest] + 2e-3).all(), (far.min(), far.max())
    assert bands[..., 1][rest].max() < 1e-3 and bands[..., 3][rest].max() < 1e-3
    assert np.abs(bands[..., 2][rest] - (1.0 - far)).max() < 2e-3


def render_full(integrator, camera):
    from mi_voldis.render.views import render_camera
    return render_camera(integrator, camera, ("full",))["full"]

def wall_and_box(with_box):
    """Fields over [-1, 1]^3: the opaque wall at z >= WALL_Z, with ``with_box`` an opaque box in front of
    it (|x|, |y| < 0.3, -0.5 <= z <= -0.1)."""
    lo, hi = -np.ones(3), np.ones(3)
    field = new_field(lo, hi, RES, 0, -20.0, 1.0 / VOXEL)
    pts, real = vertex_positions(field)
    values = np.array(field.data).reshape(-1, field.width)
    block = values[: field.layout.vertices_per_brick].copy()
    box = (np.abs(pts[:, 0]) < 0.3) & (np.abs(pts[:, 1]) < 0.3) & (pts[:, 2] >= -0.5) & (pts[:, 2] <= -0.1)
    solid = (pts[:, 2] >= WALL_Z) | (box & with_box)
    values[:, 0] = np.where(real & solid, np.log(np.expm1(200.0 * VOXEL)), -20.0)
    values[: field.layout.vertices_per_brick] = block
    field.data = from_numpy(mi.Float, values.ravel())
    return field


@pytest.mark.parametrize("removed", [True, False])
def test_mask_surfaces_tell_a_background_that_continues_the_wall_from_one_that_keeps_the_object(removed):
    """The background's median depth (``layer='bg'``) behind a box: with the box removed it ends on the
    wall, as the full field does around the mask, and its points leave the box's visual hull (the side
    cameras, 1.5 apart, see that wall outside their masks); with the box kept it ends on the box,
    inside the hull, where the full field does."""
    from types import SimpleNamespace

    from mi_voldis.bench.visible import mask_surfaces
    props = integrator_properties(SceneSpace("world"), samples=512, step_size=0.25 * VOXEL)
    full = wall_and_box(True)
    integrator = build_integrator({"full": full.plugin(), "bg": wall_and_box(not removed).plugin()}, props)
    cams = [Camera(look_at([x, 0.0, -3.0], [0.0, 0.0, 0.0]), 30.0, 32, 24) for x in (0.0, -1.5, 1.5)]
    only_full = build_integrator({"full": full.plugin(), "bg": full.plugin()}, props)
    masks = []
    for cam in cams:
        depth, hit = median_depth(only_full, cam)
        masks.append(hit & (depth < 3.0))  # the box's front face is 2.5 away, the wall 3.5
    ds = SimpleNamespace(cameras=cams, masks=np.array(masks), masked_train=np.array([1, 2]))
    assert ds.masks[0].sum() > 20
    out = mask_surfaces(ds, integrator, [0], 1, 0.9)
    assert 2.4 < out["object"] < 2.6 and 3.4 < out["ring"] < 3.7
    if removed:
        assert abs(out["background"] - out["ring"]) < 0.1
        assert out["in_hull"] < 0.5
    else:
        assert abs(out["background"] - out["object"]) < 2 * VOXEL
        assert out["in_hull"] > 0.95


def test_the_backgrounds_haze_is_counted_inside_the_region_it_hangs_in_and_not_outside():
    """A background field: the wall, and fog of extinction SIGMA only in a column |x|, |y| < HALF = 0.15 in front
    of it (z <= FOG_END). Its haze inside the pixels whose rays cross the column's middle is
    Beer-Lambert's 1 - exp(-SIGMA L) as the fog's depth L, outside it zero: a veil in the hole."""
    from mi_voldis.fit.report import background_haze
    HALF = 0.15
    lo, hi = -np.ones(3), np.ones(3)
    field = new_field(lo, hi, RES, 0, -20.0, 1.0 / VOXEL)
    pts, real = vertex_positions(field)
    values = np.array(field.data).reshape(-1, field.width)
    block = values[: field.layout.vertices_per_brick].copy()
    column = (np.abs(pts[:, 0]) < HALF) & (np.abs(pts[:, 1]) < HALF) & (pts[:, 2] <= FOG_END)
    sigma = np.where(pts[:, 2] >= WALL_Z, 200.0, np.where(column, SIGMA, 0.0)) * VOXEL
    values[:, 0] = np.where(real & (sigma > 0), np.log(np.expm1(np.maximum(sigma, 1e-12))), -20.0)
    values[: field.layout.vertices_per_brick] = block
    field.data = from_numpy(mi.Float, values.ravel())
    wall = wall_and_box(False)
    props = integrator_properties(SceneSpace("world"), samples=512, step_size=0.25 * VOXEL)
    integrator = build_integrator({"full": wall.plugin(), "bg": field.plugin()}, props)
    camera = Camera(look_at([0.0, 0.0, -3.0], [0.0, 0.0, 0.0]), 30.0, 24, 18)
    py, px = np.mgrid[0:camera.height, 0:camera.width]
    o, d = pixel_rays(camera, px.ravel() + 0.5, py.ravel() + 0.5)
    at = o + (FOG_END - o[:, 2:3]) / d[:, 2:3] * d  # where each ray leaves the fog's slab
    start = o + (-1.0 - o[:, 2:3]) / d[:, 2:3] * d
    through = (np.abs(at[:, :2]).max(1) < HALF - VOXEL) & (np.abs(start[:, :2]).max(1) < HALF - VOXEL)
    clear = (np.abs(at[:, :2]).max(1) > HALF + VOXEL) & (np.abs(start[:, :2]).max(1) > HALF + VOXEL)
    through, clear = through.reshape(camera.height, camera.width), clear.reshape(camera.height, camera.width)
    assert through.sum() > 10 and clear.sum() > 10
    inside, outside = background_haze(integrator, camera, through).values()
    expected = 1.0 - np.exp(-SIGMA * (FOG_END + 1.0))
    assert abs(inside - expected) < 0.05, (inside, expected)
    assert background_haze(integrator, camera, ~clear)["bg_haze_outside"] < 1e-3
    assert outside < inside
