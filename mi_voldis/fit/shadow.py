"""The object's shadow, found from its shape and the photos: effect masks without a user drawing them.

The object's mask leaves out its shadow, so the masked loss fits the shadow into the background and
removal keeps it. A light at p (a point light; far away, the sun) shadows a surface point x when the
segment x -> p passes through the object. The object is the cloud of its surface points (the masked
pixels' full-field surfaces, inside the masks' visual hull: a loose mask's pixels that see the scene
behind are dropped), each a ball of radius r (the point spacing). A *shadow map* from p decides it: a
perspective image from p toward the object's centre c holds per texel the nearest object distance; x
is shadowed when it lands on a covered texel farther away than that (plus r), and is not on the
object itself.

Which p. The photos are darker in a shadow than beside it, with the step at its edge, in every colour
channel (a change of material steps some channels up). For each candidate light, every view's
predicted shadow S (outside the object's mask grown by ``MASK_EDGE_PX``: a shadow cast straight down
lies against the silhouette) is compared across its edge: the band E of S within ``EDGE_PX`` of its
edge against the band R just outside it, in ell = log(linear RGB + eps), on the channel that steps
down least,

    contrast = mean_R ell - mean_E ell,      t = contrast / sqrt(var_R / |R| + var_E / |E|)

pooled over the views that have S in sight (at least ``MIN_SHARE`` of the object's area: a shadow
hidden behind the object shows only a sliver along its silhouette, where the object's soft edge and
its contact with the floor darken the photos anyway). A light must also shade the object: its side
facing p brighter than its side facing away by ``MIN_SHADING`` (:meth:`ObjectSurface.shading`, with
both sides in the views). Candidates: directions on a sphere around c (Fibonacci) at distances from 2
object radii to far away, then three rounds of refinement around the best. Best: the largest edge
contrast among the candidates whose t reaches ``SUPPORT`` of the largest t (contrast alone would
favour a sliver on one dark spot; t alone a larger shadow that also takes in dark ground beside the
true one, whose edge then falls where the photos do not step). The light must also explain the
shadow's depth and the object's shading together, with radiance = albedo (ambient + direct cos): the
shadow takes the direct term away, so its pooled contrast c on receivers at median cosine cos_r to the
light asks a direct-to-ambient ratio k = (exp(c) - 1) / cos_r, which would leave the object's points
facing the light brighter than those facing away by mean log(1 + k cos) (:meth:`ObjectSurface.
predicted_shading`). A candidate whose predicted shading exceeds the measured one by more than
``MAX_SHADING_RATIO`` is no light of this scene: a grazing light that darkens the ground by c must be
strong, and would light the object's sides far more than the photos show (on the removal family such
lights were tens of degrees off the true one; reports/notes.md). The light is kept when the step is
at least ``min_contrast``, pooled and in ``MIN_AGREE`` of the views that have the shadow in sight, or
when the object's shading explains its shadow (predicted / measured <= ``EXPLAINED_RATIO``) and the
pooled step is at least ``EXPLAINED_STEP`` x ``min_contrast``: the views' agreement guards against
dark texture that happens to line up with a candidate's edge, and so does a light that shades the
object as deeply as its shadow asks (a light shadow's edge falls below ``min_contrast`` in many views
while its pool holds).
The effect masks are then each training view's shadowed pixels, grown by ``GROW`` (penumbra, the
point cloud's coarseness).
"""
from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np

from ..cameras import pixel_rays
from ..data.types import spread
from ..io.images import srgb_to_linear
from ..metrics import diagonal_pixels, dilate
from .hull import visual_hull

MAP_SIZE = 256  # texels across the shadow map (the object fills it)
DIRECTIONS = 192  # candidate light directions on the sphere (coarse pass)
DISTANCES = (2.0, 4.0, 8.0, 16.0, 200.0)  # candidate light distances from c, in object radii
SCORE_PIXELS = 6000  # pixels per view the light search scores (strided); the masks use every pixel
SUPPORT = 0.5  # candidates whose t reaches this share of the best t compete on their edge's contrast
MIN_AGREE = 2 / 3  # a light is kept when its shadow steps down by min_contrast in this share of the views in sight
MIN_SHARE = 0.1  # a view scores a predicted shadow only if this much of the object's area is in sight
EDGE_PX = 2  # width of the bands either side of a predicted shadow's edge, in scored pixels
MASK_EDGE_PX = 2  # pixels beyond a mask no shadow is scored on (the object's antialiased edge in the photos)
EPS = 1e-3  # log luminance floor (linear)
MIN_SHADING = 0.2  # a candidate light must leave the object this much brighter (log) on its side than on the other
SIDE_SHARE = 0.1  # the object's seen points on either side of the light's terminator, at least (else unjudged)
FACING = 0.2  # |cos| between the object's normal and the light beyond which it faces the light, or away
MAX_SHADING_RATIO = 1.5  # a light's predicted object shading over the measured one, at most (module docstring)
EXPLAINED_RATIO = 1.1  # at most this ratio, the object's shading explains the shadow (module docstring) ...
EXPLAINED_STEP = 0.7  # ... and the light is kept at this fraction of min_contrast, pooled, without MIN_AGREE
MIN_RECEIVER_COS = 0.02  # receivers at a grazing angle to the light: the cosine that k divides by, at least
GROW = 0.005  # the effect masks grow by this fraction of the image diagonal (penumbra, the cloud's coarseness)
BIG = 3.0e38  # an empty texel in the min filter
KEY_MIX = np.array([1, 1 << 21, 1 << 42], np.int64)  # a cell's integer coordinates (|i| < 2^20) as one key


@dataclass
class ShadowLight:
    """The light found: its position (world), its t statistic and edge contrast (log luminance,
    pooled), the share of views whose own contrast passes, how much it shades the object
    (:meth:`ObjectSurface.shading`), whether it is kept, the shadowed receivers' median cosine to it and
    the shading its shadow predicts (:meth:`ObjectSurface.predicted_shading`)."""
    position: np.ndarray
    t: float
    contrast: float
    agree: float
    shading: float
    kept: bool
    receiver_cos: float
    predicted_shading: float

    def record(self):
        return {"light": [float(x) for x in self.position], "t": float(self.t), "contrast": float(self.contrast),
                "views_agree": float(self.agree), "shading": float(self.shading), "kept": bool(self.kept),
                "receiver_cos": float(self.receiver_cos), "predicted_shading": float(self.predicted_shading)}


def fibonacci_sphere(n):
    """``n`` unit vectors spread evenly over the sphere (n, 3)."""
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = np.pi * (1.0 + 5 ** 0.5) * k
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], -1)


def _frame(axis):
    """Two unit vectors perpendicular to the unit ``axis`` and to each other."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(axis, u)


class ShadowMap:
    """Nearest object distance per texel of a perspective image from ``light`` toward ``centre``, of the
    object ``points`` (n, 3) as balls of radius ``radius``."""

    def __init__(self, light, centre, points, radius, size=MAP_SIZE):
        self.light, self.radius, self.size = np.asarray(light, np.float64), float(radius), size
        axis = np.asarray(centre, np.float64) - self.light
        self.axis = axis / np.linalg.norm(axis)
        self.u, self.v = _frame(self.axis)
        x, y, dist = self._project(points)
        # a light among the points maps those ahead of it, within 80 degrees of its axis
        ahead = (dist > self.radius) & (np.maximum(np.abs(x), np.abs(y)) < np.tan(np.radians(80.0)))
        x, y, dist = x[ahead], y[ahead], dist[ahead]
        ball = self.radius / dist  # a ball's angular radius (tangent plane units)
        self.half = float(np.max(np.maximum(np.abs(x), np.abs(y)) + ball, initial=1e-3)) * 1.01
        self.texel = 2.0 * self.half / size
        near = np.full((size, size), np.inf, np.float32)
        ix, iy = self._texel(x, y)
        np.minimum.at(near, (np.clip(iy, 0, size - 1), np.clip(ix, 0, size - 1)), dist.astype(np.float32))
        # each point covers the texels within its ball's angular radius: a min filter of that reach
        reach = int(np.ceil(np.median(ball) / self.texel)) if len(ball) else 0
        if reach > 0:
            disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * reach + 1, 2 * reach + 1))
            near = cv2.erode(np.where(np.isfinite(near), near, BIG).astype(np.float32), disc)
            near = np.where(near >= BIG, np.inf, near)
        self.near = near

        # the object's own surface (its silhouette's soft edge lies outside the masks) is not shadow:
        # the cells of side 2 r that hold object points
        self.cell = 2.0 * self.radius
        self.object_cells = np.unique(self._keys(points))

    def _keys(self, points):
        return np.floor(np.asarray(points, np.float64) / self.cell).astype(np.int64) @ KEY_MIX

    def _project(self, points):
        q = np.asarray(points, np.float64) - self.light
        z = q @ self.axis
        with np.errstate(divide="ignore", invalid="ignore"):
            return (q @ self.u) / z, (q @ self.v) / z, np.where(z > 0, np.linalg.norm(q, axis=-1), -1.0)

    def _texel(self, x, y):
        ix = np.floor((x + self.half) / self.texel).astype(np.int64)
        iy = np.floor((y + self.half) / self.texel).astype(np.int64)
        return ix, iy

    def shadowed(self, points):
        """Bool per world point (n, 3): the object stands between it and the light."""
        x, y, dist = self._project(points)
        out = np.zeros(len(dist), bool)
        ok = dist > 0
        ix, iy = self._texel(x[ok], y[ok])
        inside = (ix >= 0) & (ix < self.size) & (iy >= 0) & (iy < self.size)
        idx = np.flatnonzero(ok)[inside]
        out[idx] = dist[idx] > self.near[iy[inside], ix[inside]] + self.radius
        out[out] = ~np.isin(self._keys(np.asarray(points)[out]), self.object_cells)
        return out


@dataclass
class ShadowViews:
    """The scored pixels of some views: per view the world points of its strided pixels (NaN where no
    surface), their unit normals (:func:`surface_points`), their log linear RGB (n, 3), and which may hold
    the shadow (outside the mask grown by ``mask_grow`` pixels)."""
    points: list
    normals: list
    ell: list
    free: list
    shapes: list
    areas: list

    @classmethod
    def of(cls, cameras, images, masks, depths, mask_grow, pixels=SCORE_PIXELS):
        points, normals, ell, free, shapes, areas = [], [], [], [], [], []
        for cam, image, mask, depth in zip(cameras, images, masks, depths):
            h, w = mask.shape
            s = max(1, int(np.ceil(np.sqrt(h * w / pixels))))
            ys, xs = np.mgrid[s // 2:h:s, s // 2:w:s]
            p, n = surface_points(cam, depth, xs, ys)
            points.append(p)
            normals.append(n)
            ell.append(np.log(srgb_to_linear(np.clip(image[ys, xs], 0, 1)).reshape(-1, 3) + EPS))
            free.append((~dilate(mask, mask_grow)[ys, xs] & np.isfinite(depth[ys, xs])).reshape(-1))
            shapes.append(ys.shape)
            areas.append(int(mask[ys, xs].sum()))
        return cls(points, normals, ell, free, shapes, areas)

    def score(self, smap, min_contrast):
        """Pooled (t, contrast) of the views' predicted shadows across their edges, the share of them
        whose own contrast reaches ``min_contrast``, and the median cosine between the shadowed
        receivers' normals and the light, over the views that have the predicted shadow in sight (at
        least ``MIN_SHARE`` of the object's area; zeros if fewer than two do). A shadow
        that stays out of sight behind the object, a sliver along its silhouette, is left out: there the
        object's soft edge and the darkening where it meets the floor would pass for one."""
        diff = wsum = var = 0.0
        views = agree = 0
        cosines = []
        for pts, nrm, ell, free, shape, area in zip(self.points, self.normals, self.ell, self.free, self.shapes,
                                                    self.areas):
            s = np.zeros(len(free), bool)
            s[free] = smap.shadowed(pts[free])
            if s.sum() < max(4, MIN_SHARE * area):
                continue
            grid = s.reshape(shape)
            ring = dilate(grid, EDGE_PX).reshape(-1) & ~s & free
            edge = s & dilate(~grid, EDGE_PX).reshape(-1)
            if ring.sum() < 4 or edge.sum() < 4:
                continue
            a, b = ell[ring], ell[edge]
            k = int(np.argmin(a.mean(0) - b.mean(0)))  # a shadow darkens every channel: the least counts
            a, b = a[:, k], b[:, k]
            c = a.mean() - b.mean()
            n = min(len(a), len(b))
            diff += n * c
            wsum += n
            var += n * n * (a.var() / len(a) + b.var() / len(b))
            views += 1
            agree += c >= min_contrast
            to_light = smap.light - pts[s]
            with np.errstate(invalid="ignore"):
                cosines.append(np.sum(nrm[s] * to_light, axis=1) / np.linalg.norm(to_light, axis=1))
        if views < 2:  # one view is no multi-view evidence
            return 0.0, 0.0, 0.0, 0.0
        cosines = np.concatenate(cosines)
        cosines = cosines[np.isfinite(cosines)]  # normals are NaN at depth edges
        return diff / np.sqrt(var + 1e-12), diff / wsum, agree / views, float(np.median(cosines)) if len(
            cosines) else 0.0


def surface_points(camera, depth, xs, ys):
    """World points (n, 3) of the depth map ``depth`` at the pixel grid ``xs``, ``ys`` (2D, regular) and
    their unit normals, from central differences on that grid, turned toward the camera (NaN where a
    neighbour has no surface, and on the grid's border)."""
    o, d = pixel_rays(camera, xs.reshape(-1) + 0.5, ys.reshape(-1) + 0.5)
    pts = o + depth[ys, xs].reshape(-1)[:, None] * d
    grid = pts.reshape(xs.shape + (3,))
    du, dv = np.full_like(grid, np.nan), np.full_like(grid, np.nan)
    du[:, 1:-1] = grid[:, 2:] - grid[:, :-2]
    dv[1:-1] = grid[2:] - grid[:-2]
    n = np.cross(du, dv).reshape(-1, 3)
    with np.errstate(invalid="ignore", divide="ignore"):
        n /= np.linalg.norm(n, axis=1, keepdims=True)
    n *= np.where(np.sum(n * (o - pts), axis=1) < 0, -1.0, 1.0)[:, None]
    return pts, n


@dataclass
class ObjectSurface:
    """The object's surface as the views see it: world points (n, 3) of each view's masked pixels (the
    mask eroded by a pixel: its edge mixes in the background) at the full field's depth, their unit
    normals, the log luminance of the photos there, and the median spacing of neighbouring pixels'
    points (which the balls' radius follows)."""
    points: np.ndarray
    normals: np.ndarray
    ell: np.ndarray
    spacing: float

    @classmethod
    def of(cls, cameras, images, masks, depths, erode=1):
        pts, nrm, ell, spacing = [], [], [], []
        for cam, image, mask, depth in zip(cameras, images, masks, depths):
            h, w = mask.shape
            ys, xs = np.mgrid[0:h, 0:w]
            p, n = surface_points(cam, depth, xs, ys)
            inner = (mask & ~dilate(~mask, erode) & np.isfinite(depth)).reshape(-1)
            if not inner.any():
                continue
            right = np.roll(p.reshape(h, w, 3), -1, axis=1).reshape(-1, 3)  # the next pixel's point
            spacing.append(np.linalg.norm(right - p, axis=1)[inner & np.roll(inner.reshape(h, w), -1, 1).reshape(-1)])
            pts.append(p[inner])
            nrm.append(n[inner])
            lum = srgb_to_linear(np.clip(image, 0, 1)) @ np.array([0.2126, 0.7152, 0.0722])
            ell.append(np.log(lum.reshape(-1)[inner] + EPS))
        if not pts:
            return cls(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), 0.0)
        spacing = np.concatenate(spacing)
        return cls(np.concatenate(pts), np.concatenate(nrm), np.concatenate(ell),
                   float(np.median(spacing)) if len(spacing) else 0.0)

    @cached_property
    def _columns(self):
        """The points' and normals' coordinates as six contiguous arrays (:meth:`facing`)."""
        return [np.ascontiguousarray(a[:, i]) for a in (self.points, self.normals) for i in range(3)]

    def facing(self, light):
        """Per point, the cosine between its normal and the direction to ``light``: (l - x) . n / |l - x|
        (NaN where the normal is). Summed coordinate by coordinate in the order NumPy's row sums take, so
        the same bits as those, eight times faster on the columns: the light search asks it of every
        candidate (statue: 0.5 M points, 1,335 candidates)."""
        px, py, pz, nx, ny, nz = self._columns
        light = np.asarray(light, np.float64)
        dx, dy, dz = light[0] - px, light[1] - py, light[2] - pz
        with np.errstate(invalid="ignore"):
            return (dx * nx + dy * ny + dz * nz) / np.sqrt(dx * dx + dy * dy + dz * dz)

    def inside(self, keep):
        """The points where ``keep`` (bool per point) holds."""
        return ObjectSurface(self.points[keep], self.normals[keep], self.ell[keep], self.spacing)

    def shading(self, light):
        """How much brighter (log luminance) the object is where it faces ``light`` than where it faces
        away (|cos| > ``FACING``; normals NaN at depth edges left out): a light that lights the
        object shades it so; a light no shadow came from need not."""
        cos = self.facing(light)
        lit, dark = cos > FACING, cos < -FACING
        if min(lit.sum(), dark.sum()) < max(16, SIDE_SHARE * len(cos)):  # the views see too little of a side
            return 0.0
        return float(self.ell[lit].mean() - self.ell[dark].mean())

    def predicted_shading(self, light, contrast, receiver_cos):
        """The shading :meth:`shading` would measure were ``light`` the light whose shadow darkens
        receivers at median cosine ``receiver_cos`` to it by ``contrast`` (log), radiance = albedo
        (ambient + direct cos): k = (exp(contrast) - 1) / cos_r, then mean log(1 + k cos) over the
        points facing the light (the points facing away take ambient alone)."""
        k = np.expm1(max(contrast, 0.0)) / max(receiver_cos, MIN_RECEIVER_COS)
        cos = self.facing(light)
        lit = cos > FACING
        return float(np.mean(np.log1p(k * cos[lit]))) if lit.any() else 0.0


def find_light(views, surface, min_contrast, min_agree=MIN_AGREE, max_points=20000, seed=0):
    """The light whose shadow of the object (``surface``, :class:`ObjectSurface`) best explains the
    darkening of ``views`` (:class:`ShadowViews`) among the lights that shade the object itself by at
    least ``MIN_SHADING`` (:meth:`ObjectSurface.shading`): a coarse search over directions and
    distances, then three rounds of refinement around the best. Returns the :class:`ShadowLight` and
    the occluder (points, ball radius, centre) for :func:`shadow_masks`. At most ``max_points`` points
    cast the shadow (a random subset, their spacing grown to match); each is a ball of radius spacing /
    sqrt 2, which closes the gaps of a square grid of that spacing."""
    obj, spacing = surface.points, surface.spacing
    if len(obj) > max_points:
        spacing *= np.sqrt(len(obj) / max_points)
        obj = obj[np.random.default_rng(seed).choice(len(obj), max_points, replace=False)]
    radius = spacing / np.sqrt(2.0)
    centre = obj.mean(0)
    size = float(np.percentile(np.linalg.norm(obj - centre, axis=1), 95))
    none = (0.0, -np.inf, 0.0, 0.0)

    def evaluate(p):
        shading = surface.shading(p)
        if shading < MIN_SHADING:
            return none
        s = views.score(ShadowMap(p, centre, obj, radius), min_contrast)
        if s[1] > 0 and surface.predicted_shading(p, s[1], s[3]) > MAX_SHADING_RATIO * shading:
            return none  # a shadow this deep from there would shade the object far more than it is
        return s

    cands = [centre + size * r * d for r in DISTANCES for d in fibonacci_sphere(DIRECTIONS)]
    scores = [evaluate(p) for p in cands]
    floor = SUPPORT * max(s[0] for s in scores)

    def better(s, than):  # the sharper edge among the candidates the photos support well
        return s[0] >= floor and s[1] > than[1]

    p, sc = None, none
    for q, s in zip(cands, scores):
        if better(s, sc):
            p, sc = q, s
    if p is None:  # no light shades the object, or no shadow darkens the photos: nothing to search around
        return ShadowLight(centre, 0.0, 0.0, 0.0, 0.0, False, 0.0, 0.0), (obj, radius, centre)
    spread, factor = np.sqrt(4.0 * np.pi / DIRECTIONS), 2.0  # the coarse grid's spacing (radians, ratio)
    for _ in range(3):
        offset = p - centre
        dist, axis = np.linalg.norm(offset), offset / np.linalg.norm(offset)
        u, v = _frame(axis)
        for a in np.linspace(-spread, spread, 5):
            for b in np.linspace(-spread, spread, 5):
                for f in factor ** np.linspace(-1.0, 1.0, 5):
                    d = axis + a * u + b * v
                    q = centre + max(f * dist, 1.2 * size) * d / np.linalg.norm(d)
                    s = evaluate(q)
                    if better(s, sc):
                        p, sc = q, s
        spread, factor = spread / 2.5, np.sqrt(factor)
    t, contrast, agree, receiver_cos = sc
    shading, predicted = surface.shading(p), surface.predicted_shading(p, contrast, receiver_cos)
    kept = (contrast >= min_contrast and agree >= min_agree) or (
        contrast >= EXPLAINED_STEP * min_contrast and predicted <= EXPLAINED_RATIO * shading)
    return ShadowLight(p, t, contrast, agree, shading, kept, receiver_cos, predicted), (obj, radius, centre)


def shadow_masks(light, occluder, cameras, masks, depths, grow):
    """Per view the pixels (H, W) bool outside its mask whose full-field surface ``light`` leaves in the
    object's shadow (``occluder``: the points, radius and centre :func:`find_light` used), grown by
    ``grow`` pixels; all False for a view without a depth map."""
    obj, radius, centre = occluder
    smap = ShadowMap(light.position, centre, obj, radius)
    out = []
    for cam, mask, depth in zip(cameras, masks, depths):
        h, w = mask.shape
        s = np.zeros(h * w, bool)
        if depth is not None:
            ok = np.flatnonzero(np.isfinite(depth.reshape(-1)))
            py, px = np.divmod(ok, w)
            o, d = pixel_rays(cam, px + 0.5, py + 0.5)
            s[ok] = smap.shadowed(o + depth.reshape(-1)[ok, None] * d)
        out.append(dilate(s.reshape(h, w), grow) & ~mask)
    return np.stack(out)


def find_shadow(inputs, state, views=12, depths=None):
    """The object's shadow as effect masks (N, H, W) bool on the masked training views of ``inputs``'
    dataset (False elsewhere), grown by ``GROW``, from the full field's median depths of every masked
    training view, ``views`` of them spread over the set scored; None when no light passes
    ``shadow_contrast``. Also returns the light's record. ``depths``: the full field's median depth maps
    by view, read and filled (:func:`~mi_voldis.fit.lift.training_depths`)."""
    from .lift import training_depths
    ds = inputs.ds
    return shadow_of_depths(ds, inputs.cfg, training_depths(inputs, state, count=len(ds.train), median=True,
                                                            memo=depths), views)


def shadow_of_depths(ds, cfg, depth, views=12):
    """:func:`find_shadow` from the full field's median depth maps ``depth`` (view -> (H, W), NaN where
    no surface) of the dataset ``ds``'s masked training views, with the settings ``cfg``."""
    masked = [v for v in ds.masked_train if v in depth]
    if not masked:
        return None, None
    cams, masks, depths = ([seq[v] for v in masked] for seq in (ds.cameras, ds.masks, depth))
    grow = diagonal_pixels(cfg.hull_dilation, ds.size)
    surface = ObjectSurface.of(cams, [ds.images[v] for v in masked], masks, depths)
    # a masked pixel's ray may end on the scene behind the object (a loose mask): inside the visual hull
    # only, the object's own surface stays
    surface = surface.inside(visual_hull(surface.points, cams, masks, grow, cfg.hull_min_views, depths))
    if len(surface.points) < 16:
        return None, None
    pick = spread(len(masked), views)
    scored = ShadowViews.of([cams[k] for k in pick], [ds.images[masked[k]] for k in pick], [masks[k] for k in pick],
                            [depths[k] for k in pick], MASK_EDGE_PX)
    light, occluder = find_light(scored, surface, cfg.shadow_contrast, seed=cfg.seed)
    if not light.kept:
        return None, light.record()
    shadow = np.zeros(ds.masks.shape, bool)
    shadow[masked] = shadow_masks(light, occluder, cams, masks, depths, diagonal_pixels(GROW, ds.size))
    return shadow, light.record()
