"""The object's shadow found from its shape and the photos (mi_voldis.fit.shadow), on an analytic scene:
a sphere over the floor y = FLOOR_Y, a point light, a textured floor, cameras around."""
import numpy as np

from mi_voldis.cameras import Camera, look_at, pixel_rays
from mi_voldis.fit.shadow import MASK_EDGE_PX, ObjectSurface, ShadowMap, ShadowViews, find_light, shadow_masks
from mi_voldis.io.images import linear_to_srgb

FLOOR_Y = -0.5
CENTRE, RADIUS = np.array([0.0, -0.15, 0.0]), 0.3
LIGHT = np.array([-1.0, 2.0, 0.6])


def _sphere_hit(o, d, centre=CENTRE, radius=RADIUS):
    oc = o - centre
    b = np.sum(oc * d, axis=-1)
    disc = b * b - (np.sum(oc * oc, axis=-1) - radius ** 2)
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    return np.where((disc > 0) & (t > 0), t, np.inf)


def _clearance(points, light):
    """Distance from the sphere's centre to the segment from each point to ``light``."""
    seg = light - points
    t = np.clip(np.sum((CENTRE - points) * seg, axis=1) / np.sum(seg * seg, axis=1), 0.0, 1.0)
    return np.linalg.norm(points + t[:, None] * seg - CENTRE, axis=1)


def _in_shadow(points, light):
    """Exact, for points outside the sphere: the segment from each point to ``light`` meets it."""
    return _clearance(points, light) < RADIUS


def scene(light=LIGHT, shade_from="light", views=6, size=(96, 72), direct=0.75, shadow_factor=0.25):
    """Cameras on a ring looking at the sphere; per camera its depth, the sphere's mask, the exact shadow
    on the floor, and a photo: a checkered floor (albedo 0.35 / 0.55) lit by ``light`` (``shadow_factor``
    of it in shadow: ambient) or, with ``light`` None, evenly; the sphere (albedo 0.5) shaded by the light at
    ``shade_from`` (the same light by default; None: evenly), ``direct`` of its light at normal incidence
    the light's and the rest ambient."""
    shade_from = light if isinstance(shade_from, str) else shade_from
    cams, depths, masks, shadows, photos = [], [], [], [], []
    for a in np.linspace(0.0, 2 * np.pi, views, endpoint=False):
        cam = Camera(look_at([2.2 * np.cos(a), 1.3, 2.2 * np.sin(a)], [0.0, FLOOR_Y, 0.0]), 60.0, *size)
        py, px = np.mgrid[0:cam.height, 0:cam.width]
        o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
        with np.errstate(divide="ignore"):
            floor_t = np.where(d[:, 1] < 0, (FLOOR_Y - o[:, 1]) / d[:, 1], np.inf)
        ball_t = _sphere_hit(o, d)
        mask = ball_t < floor_t
        depth = np.minimum(ball_t, floor_t)
        pts = o + np.where(np.isfinite(depth), depth, 0.0)[:, None] * d
        albedo = np.where((np.floor(pts[:, 0] * 5) + np.floor(pts[:, 2] * 5)) % 2 == 0, 0.35, 0.55)
        shade = np.zeros(len(pts), bool)
        floor = ~mask & np.isfinite(depth)
        if light is not None:
            shade[floor] = _in_shadow(pts[floor], light)
        ball = 0.5
        if shade_from is not None:
            normal = (pts - CENTRE) / RADIUS
            to = (shade_from - pts) / np.linalg.norm(shade_from - pts, axis=1, keepdims=True)
            ball = 0.5 * (1.0 - direct + direct * np.maximum(np.sum(normal * to, axis=1), 0.0))
        lum = np.where(mask, ball, albedo * np.where(shade, shadow_factor, 1.0))
        cams.append(cam)
        depths.append(np.where(np.isfinite(depth), depth, np.nan).reshape(cam.height, cam.width))
        masks.append(mask.reshape(cam.height, cam.width))
        shadows.append(shade.reshape(cam.height, cam.width))
        photos.append(np.repeat(linear_to_srgb(lum).reshape(cam.height, cam.width, 1), 3, axis=2))
    return cams, depths, masks, shadows, photos


def test_shadow_map_matches_the_exact_shadow_of_a_sphere():
    """Floor points under the sphere's point cloud (its visible surface from six views, balls of the
    pixel spacing): the shadow map agrees with the exact segment test except within a ball's reach of
    the shadow's edge."""
    cams, depths, masks, _, photos = scene()
    surface = ObjectSurface.of(cams, photos, masks, depths)
    obj, spacing = surface.points, surface.spacing
    assert len(obj) > 1000 and 0.0 < spacing < 0.05
    np.testing.assert_allclose(np.linalg.norm(obj - CENTRE, axis=1), RADIUS, atol=1e-6)
    normal = surface.normals[np.isfinite(surface.normals).all(1)]
    expected = (obj[np.isfinite(surface.normals).all(1)] - CENTRE) / RADIUS
    assert np.median(np.sum(normal * expected, axis=1)) > 0.99  # central differences on the sphere
    smap = ShadowMap(LIGHT, obj.mean(0), obj, spacing)
    xs, zs = np.meshgrid(np.linspace(-1.5, 1.5, 121), np.linspace(-1.5, 1.5, 121))
    floor = np.stack([xs.ravel(), np.full(xs.size, FLOOR_Y), zs.ravel()], -1)
    exact = _in_shadow(floor, LIGHT)
    got = smap.shadowed(floor)
    assert exact.sum() > 100
    # points clearly inside / outside (exact test with the sphere shrunk / grown by 3 balls) agree, but
    # for the odd gap in the cloud where the views see the sphere's underside at a grazing angle
    clearance = _clearance(floor, LIGHT)
    shrunk, grown = clearance < RADIUS - 3 * spacing, clearance < RADIUS + 3 * spacing
    assert shrunk.sum() > 100 and got[shrunk].mean() > 0.98
    assert not got[~grown].any()
    # points between the light and the sphere are lit
    assert not smap.shadowed((CENTRE + 0.6 * (LIGHT - CENTRE))[None])[0]


def test_find_light_recovers_a_point_light_and_its_shadow_masks():
    cams, depths, masks, shadows, photos = scene()
    surface = ObjectSurface.of(cams, photos, masks, depths)
    views = ShadowViews.of(cams, photos, masks, depths, mask_grow=1)
    light, occluder = find_light(views, surface, min_contrast=0.2)
    assert light.kept and light.contrast > 0.8  # the shadow is 4x darker: log 4 = 1.39, less the edges
    assert light.shading > 0.2
    # the light's direction from the sphere within 10 degrees
    cos = np.dot(light.position - CENTRE, LIGHT - CENTRE) / np.linalg.norm(light.position - CENTRE) / np.linalg.norm(
        LIGHT - CENTRE)
    assert cos > np.cos(np.radians(10))
    found = shadow_masks(light, occluder, cams, masks, depths, grow=1)
    inter = sum((f & s).sum() for f, s in zip(found, shadows))
    union = sum((f | s).sum() for f, s in zip(found, shadows))
    assert inter / union > 0.7
    assert not any((f & m).any() for f, m in zip(found, masks))


def test_a_shadow_cast_straight_down_is_found_against_the_silhouette():
    """A light above the sphere: its shadow shows only as a crescent against the silhouette (at most
    about 6 pixels out in these views); the views score it from ``MASK_EDGE_PX`` beyond the masks, so
    the light is found and kept."""
    above = np.array([0.05, 2.5, 0.0])
    cams, depths, masks, shadows, photos = scene(light=above)
    views = ShadowViews.of(cams, photos, masks, depths, mask_grow=MASK_EDGE_PX)
    light, occluder = find_light(views, ObjectSurface.of(cams, photos, masks, depths), min_contrast=0.5)
    assert light.kept and light.contrast > 0.8
    cos = np.dot(light.position - CENTRE, above - CENTRE) / np.linalg.norm(light.position - CENTRE) / np.linalg.norm(
        above - CENTRE)
    assert cos > np.cos(np.radians(10))
    found = shadow_masks(light, occluder, cams, masks, depths, grow=1)
    assert sum((f & s).sum() for f, s in zip(found, shadows)) / sum((f | s).sum() for f, s in zip(found, shadows)) > 0.5


def test_no_light_is_kept_without_a_shadow():
    """Evenly lit, the floor checkered: the best candidate's contrast (tiles it happens to cover) stays
    under the floor, nothing is kept."""
    cams, depths, masks, _, photos = scene(light=None, shade_from=LIGHT)
    views = ShadowViews.of(cams, photos, masks, depths, mask_grow=1)
    found, _ = find_light(views, ObjectSurface.of(cams, photos, masks, depths), min_contrast=0.2)
    assert not found.kept


def test_a_dark_patch_the_objects_shading_contradicts_is_not_its_shadow():
    """The floor darkened exactly as LIGHT's shadow would, but the sphere lit from the opposite
    direction (from below: its top, which the views see, dark): no light both casts that shadow and
    shades the sphere so; an evenly lit sphere is shaded by no light."""
    for shade_from in (2 * CENTRE - LIGHT, None):
        cams, depths, masks, _, photos = scene(shade_from=shade_from)
        surface = ObjectSurface.of(cams, photos, masks, depths)
        assert surface.shading(LIGHT) < 0.2
        found, _ = find_light(ShadowViews.of(cams, photos, masks, depths, mask_grow=1), surface, min_contrast=0.2)
        cos = np.dot(found.position - CENTRE, LIGHT - CENTRE) / np.linalg.norm(found.position - CENTRE) / \
            np.linalg.norm(LIGHT - CENTRE)
        assert not found.kept or cos < np.cos(np.radians(30))


def test_a_light_among_the_points_maps_those_ahead_of_it():
    """A candidate light inside the object's cloud (the refinement may step there): the map holds the
    points ahead of it only, stays finite, and a point behind the light is never shadowed."""
    cams, depths, masks, _, photos = scene()
    surface = ObjectSurface.of(cams, photos, masks, depths)
    smap = ShadowMap(CENTRE + np.array([0.0, 0.2, 0.0]), CENTRE, surface.points, surface.spacing)
    assert np.isfinite(smap.half) and np.isfinite(smap.near).any()
    assert not smap.shadowed((CENTRE + np.array([0.0, 2.0, 0.0]))[None])[0]  # behind the light
    near = smap.near[np.isfinite(smap.near)]
    assert near.min() > smap.radius and near.max() < 2 * RADIUS  # only the sphere's far side, ahead of it


def test_predicted_shading_follows_the_two_term_model():
    """Points facing the light at cosine c: log(1 + k c) with k = (exp(contrast) - 1) / cos_r, averaged
    over the points past FACING; the points facing away do not count."""
    light = np.array([0.0, 10.0, 0.0])
    cos = np.array([1.0, 0.5, 0.1, -0.6])  # the last two: not facing it (0.1 < FACING) or facing away
    normals = np.stack([np.sqrt(1 - cos ** 2), cos, np.zeros(4)], -1)
    surface = ObjectSurface(np.zeros((4, 3)), normals, np.zeros(4), 0.01)
    contrast, receiver_cos = np.log(3.0), 0.5  # k = 2 / 0.5 = 4
    want = np.mean(np.log1p(4.0 * cos[:2]))
    assert np.isclose(surface.predicted_shading(light, contrast, receiver_cos), want, rtol=1e-6)
    # a grazing receiver asks a far stronger light for the same contrast
    assert surface.predicted_shading(light, contrast, 0.05) > 2 * want


def test_facing_is_the_cosine_to_the_light_bit_for_bit_as_row_sums_give_it():
    """Analytic: a point at the origin with normal +z faces a light above it at cosine 1, one beside it
    at 0, one below at -1, one at 45 degrees at 1/sqrt 2; a NaN normal gives NaN. On random points the
    column sums give the very bits of NumPy's row sums (the light search's decisions do not move)."""
    normals = np.array([[0.0, 0.0, 1.0]] * 4 + [[np.nan] * 3])
    surface = ObjectSurface(np.zeros((5, 3)), normals, np.zeros(5), 0.01)
    for light, want in (([0, 0, 2], 1.0), ([3, 0, 0], 0.0), ([0, 0, -1], -1.0), ([1, 0, 1], 0.5 ** 0.5)):
        cos = surface.facing(light)
        assert np.allclose(cos[:4], want, atol=1e-15) and np.isnan(cos[4])
    rng = np.random.default_rng(3)
    points, normals = rng.normal(size=(1000, 3)), rng.normal(size=(1000, 3))
    light = np.array([0.3, 2.0, -1.1])
    rows = np.sum((light - points) * normals, axis=1) / np.linalg.norm(light - points, axis=1)
    assert np.array_equal(ObjectSurface(points, normals, np.zeros(1000), 0.01).facing(light), rows)


def test_a_grazing_lights_shadow_the_objects_shading_cannot_match_is_not_kept(monkeypatch):
    """The floor darkened 4x where a light 10 degrees above it would shadow the sphere, the sphere lit
    by that light with half its light direct: log(1 + c) on its lit side, where a light that strong
    at that angle would leave about log(1 + 15 c). The old rule (shading above MIN_SHADING, the step
    in the photos) kept it; the shading check leaves it out."""
    from mi_voldis.fit import shadow
    grazing = np.array([-2.6, 0.0, 0.8])
    cams, depths, masks, _, photos = scene(light=grazing, direct=0.5)
    surface = ObjectSurface.of(cams, photos, masks, depths)
    views = ShadowViews.of(cams, photos, masks, depths, mask_grow=1)
    assert surface.shading(grazing) > shadow.MIN_SHADING
    found, _ = find_light(views, surface, min_contrast=0.2)
    assert not found.kept or found.predicted_shading <= shadow.MAX_SHADING_RATIO * found.shading
    cos = np.dot(found.position - CENTRE, grazing - CENTRE) / np.linalg.norm(found.position - CENTRE) / \
        np.linalg.norm(grazing - CENTRE)
    assert not found.kept or cos < np.cos(np.radians(20))
    monkeypatch.setattr(shadow, "MAX_SHADING_RATIO", np.inf)
    old, _ = find_light(views, surface, min_contrast=0.2)
    assert old.kept and np.dot(old.position - CENTRE, grazing - CENTRE) / np.linalg.norm(
        old.position - CENTRE) / np.linalg.norm(grazing - CENTRE) > np.cos(np.radians(20))


def test_a_light_shadow_the_objects_shading_explains_is_kept_though_few_views_pass_the_step(monkeypatch):
    """The floor only 35% darker in the shadow (log step 0.43, less at the blurred edge): under 0.5 in
    most views, so the views' agreement fails; the sphere, shaded by the same light, explains the shadow
    (predicted / measured shading under EXPLAINED_RATIO), so the light is kept at EXPLAINED_STEP x 0.5."""
    from mi_voldis.fit import shadow
    cams, depths, masks, shadows, photos = scene(shadow_factor=0.65)
    surface = ObjectSurface.of(cams, photos, masks, depths)
    views = ShadowViews.of(cams, photos, masks, depths, mask_grow=1)
    found, occluder = find_light(views, surface, min_contrast=0.5)
    assert found.agree < shadow.MIN_AGREE and shadow.EXPLAINED_STEP * 0.5 <= found.contrast < 0.5
    assert found.predicted_shading <= shadow.EXPLAINED_RATIO * found.shading and found.kept
    cos = np.dot(found.position - CENTRE, LIGHT - CENTRE) / np.linalg.norm(found.position - CENTRE) / np.linalg.norm(
        LIGHT - CENTRE)
    assert cos > np.cos(np.radians(10))
    monkeypatch.setattr(shadow, "EXPLAINED_RATIO", 0.0)  # without the shading's explanation: the old rule
    assert not find_light(views, surface, min_contrast=0.5)[0].kept
