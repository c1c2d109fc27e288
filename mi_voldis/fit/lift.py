"""A consistent prior for the background no view sees: inpaint one reference view in 2D, lift it into 3D.

For a reference training view r, each masked pixel's ray is searched, from the object's front
outwards, for the first point that another view sees unmasked (:mod:`mi_voldis.fit.visibility`): that
point, with the colour those views observe there, is the background behind the object. The masked
pixels where no view sees anything form the *hole*, inpainted in 2D (colour with an inpainter,
:mod:`mi_voldis.inpaint2d`, from the photo and the observed colours around it; depth as disparity,
continuing the surrounding surfaces). Every masked pixel then becomes a surface point X = o + t d with
its colour, written into the background field as an opaque surface at the nearest lattice vertices,
inside the object's visual hull only (outside it every vertex is constrained by some unmasked view).
Every view sees one surface there, so the fill is consistent across views by construction; the refit
with the masked loss then refines what views see.

Several reference views are inpainted in turn, each only where the background so far leaves a hole
(:func:`lift_prior`), so that what one view cannot see behind the object another supplies.
"""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..cameras import pixel_rays
from ..data.types import spread
from ..device import from_numpy
from ..field.activations import logit
from ..field.state import density_raw_for_alpha, resample
from ..inpaint2d import fill_disparity, inpainter, inpainter_name
from ..metrics import diagonal_pixels, dilate
from ..render.surface import median_depth
from ..render.views import render_camera
from .fields import fit_integrator
from .hull import visual_hull
from .visibility import pixel_points, seen_elsewhere

SURFACE_ALPHA = 0.99  # opacity of one voxel's length of a lifted surface


def lattice_cells(field, space, points, halo=0):
    """The lattice vertices (i, j, k) of the cell holding each world point, grown by ``halo`` vertices on
    every side (int (n, (2 + 2 halo)^3, 3)), and whether the cell lies in the lattice."""
    scene = space.from_world_np(points)
    m = field.to_world
    local = (scene - m[:3, 3]) / np.diag(m)[:3]
    base = np.floor(local * (np.array(field.shape) - 1)).astype(np.int64)
    r = np.arange(-halo, 2 + halo)
    corners = np.stack(np.meshgrid(r, r, r, indexing="ij"), -1).reshape(-1, 3)
    ijk = np.clip(base[:, None, :] + corners[None], 0, np.array(field.shape) - 1)
    ok = np.all((base >= 0) & (base + 1 < np.array(field.shape)), axis=1)
    return ijk, ok


def write_surface(field, space, points, colors, allowed):
    """``field`` with an opaque surface (``SURFACE_ALPHA`` per voxel) of display colours ``colors`` at the
    corners of the cells holding world ``points`` (so that no ray slips between written vertices), and
    the colour alone one vertex further (colour is interpolated before its activation: a black neighbour
    would darken the surface's edges), where ``allowed(field)`` (Float per stored vertex) is > 0 (the
    object's hull: outside it the background is what the views saw). Bricks
    the points need are allocated first. Returns the new field and the written lattice keys."""
    voxel = float(np.max(np.diag(field.to_world)[:3] / (np.array(field.shape) - 1)))
    surface = density_raw_for_alpha(SURFACE_ALPHA, voxel, field.density_scale)
    keys = np.zeros(0, np.int64)
    for halo in (1, 0):  # the colour's halo first, then the surface over it
        ijk, ok = lattice_cells(field, space, points, halo)
        if not ok.any():
            break
        n = ijk.shape[1]
        ijk, rgb = ijk[ok].reshape(-1, 3), np.repeat(colors[ok], n, axis=0)
        s = field.layout.shift
        need = np.zeros(field.layout.table.shape, bool)
        need[ijk[:, 2] >> s, ijk[:, 1] >> s, ijk[:, 0] >> s] = True
        if (need & (field.layout.table == 0)).any():
            field = resample(field, None, need | (field.layout.table > 0))
        x, y, _ = field.shape
        keys, inverse = np.unique((ijk[:, 2] * y + ijk[:, 1]) * x + ijk[:, 0], return_inverse=True)
        inverse = inverse.reshape(-1)
        mean = np.zeros((len(keys), 3))
        np.add.at(mean, inverse, rgb)
        mean /= np.bincount(inverse, minlength=len(keys))[:, None]
        k, rest = np.divmod(keys, x * y)
        j, i = np.divmod(rest, x)
        address = field.layout.address(*(from_numpy(mi.UInt32, a.astype(np.uint32)) for a in (i, j, k)))
        inside = np.array(dr.gather(mi.Float, allowed(field), address) > 0)
        if not inside.any():  # every point lands where the background may not change
            return field, keys[inside]
        address = dr.gather(mi.UInt32, address, from_numpy(mi.UInt32, np.flatnonzero(inside).astype(np.uint32)))
        mean, keys = mean[inside], keys[inside]
        data = dr.copy(field.data)
        w = field.width
        if halo == 0:
            dr.scatter(data, surface, address * w)
        raw = logit(mean).astype(np.float32)
        for c in range(1, field.channels):  # the DC term carries the colour, higher orders none
            value = from_numpy(mi.Float, raw[:, c - 1]) if c <= 3 else mi.Float(0.0)
            dr.scatter(data, value, address * w + c)
        dr.eval(data)
        field = field.with_data(data)
    return field, keys


def ray_keys(field, space, camera, pixels, t_end, keep=None, chunk=1 << 21):
    """Lattice keys of every vertex of ``field`` nearest to the rays of flat ``pixels`` of ``camera``,
    from the camera to ``t_end`` (per pixel, along the ray), sampled every half voxel of scene space;
    ``keep(world points) -> Bool``: which of those vertices count (default: all)."""
    pixels = np.asarray(pixels)
    if not len(pixels):
        return np.zeros(0, np.int64)
    py, px = np.divmod(pixels, camera.width)
    o, d = pixel_rays(camera, px + 0.5, py + 0.5)
    m = field.to_world
    voxel = float(np.max(np.diag(m)[:3] / (np.array(field.shape) - 1)))
    length = np.linalg.norm(space.from_world_np(o + t_end[:, None] * d) - space.from_world_np(o), axis=1)
    n = int(np.clip(np.ceil(length.max() / (0.5 * voxel)), 2, 4096))
    x, y, _ = field.shape
    keys = []
    rows = max(1, chunk // n)
    for a in range(0, len(pixels), rows):
        f = np.linspace(0.0, 1.0, n)[None, :, None]
        pts = o[a:a + rows, None] + f * (t_end[a:a + rows, None, None] * d[a:a + rows, None])
        scene = space.from_world_np(pts.reshape(-1, 3))
        ijk = np.round((scene - m[:3, 3]) / np.diag(m)[:3] * (np.array(field.shape) - 1)).astype(np.int64)
        ijk = ijk[np.all((ijk >= 0) & (ijk < np.array(field.shape)), axis=1)]
        keys.append(np.unique((ijk[:, 2] * y + ijk[:, 1]) * x + ijk[:, 0]))
    keys = np.unique(np.concatenate(keys))
    if keep is not None and len(keys):
        k, rest = np.divmod(keys, x * y)
        j, i = np.divmod(rest, x)
        local = np.stack([i, j, k], -1) / (np.array(field.shape) - 1)
        keys = keys[keep(space.to_world_np(local * np.diag(m)[:3] + m[:3, 3]))]
    return keys


def object_ray_keys(inputs, field, views, depth, dilation=0.01, reach=0.9, fraction=0.5):
    """Lattice keys of the vertices of ``field`` that only the object can occupy: on the masked rays
    (masks grown by ``dilation`` of the diagonal: edge pixels are partly the object) of ``views`` (full
    field depth maps ``depth[view]``), from the camera to ``reach`` times the background's depth there
    (the disparity fill of the depth around the mask), and inside the grown masks of at least
    ``fraction`` of the training views that see them (what most views see stays). On a masked ray
    nothing but the object stands in front of the background, so whatever the full field holds there
    that is not the background's is the object's, wherever the visual hull ends."""
    ds = inputs.ds
    grow = diagonal_pixels(dilation, ds.size)
    cams, masks = [ds.cameras[u] for u in ds.masked_train], ds.masks[ds.masked_train]

    def objectish(points):
        return visual_hull(points, cams, masks, grow, fraction)

    keys = [np.zeros(0, np.int64)]
    for u in views:
        region = dilate(ds.masks[u], grow)
        pixels = np.flatnonzero(region)
        behind = fill_disparity(depth[u], region, camera=ds.cameras[u]).reshape(-1)[pixels]
        keys.append(ray_keys(field, inputs.space, ds.cameras[u], pixels, reach * behind, objectish))
    return np.unique(np.concatenate(keys))


def training_depths(inputs, state, count=24, extra=(), median=False, memo=None):
    """Full-field depth maps of ``count`` training views spread over the set (and of ``extra``); NaN
    where a ray ends on nothing (opacity below a half). The expected depth, or with ``median`` the
    median (where the transmittance falls to a half: a faint haze in front does not pull it nearer).
    ``memo``: a dict of median depth maps by view, read and filled (while the full field stays as it
    is, the steps that start the background each ask for these renders)."""
    ds = inputs.ds
    train = list(ds.train)
    pick = spread(len(train), count)
    views = sorted(set(train[k] for k in pick) | set(extra))
    integrator = fit_integrator(inputs, state)
    memo = {} if memo is None or not median else memo
    out = {}
    for u in views:
        if median:
            if u not in memo:
                depth, hit = median_depth(integrator, ds.cameras[u])
                memo[u] = np.where(hit, depth, np.nan)
            out[u] = memo[u]
        else:
            _, alpha, depth = render_camera(integrator, ds.cameras[u], ("full",))["full"]
            out[u] = np.where(alpha > 0.5, depth, np.nan)
    return out


def keys_mask(field, keys):
    """Bool per stored vertex of ``field``: its lattice key ((k Y + j) X + i) is among ``keys``."""
    coords, inside = field.layout.vertex_coords()
    x, y, _ = field.shape
    own = (coords[:, 2] * y + coords[:, 1]) * x + coords[:, 0]
    return from_numpy(mi.Bool, inside & np.isin(own, keys))


def lift_pixels(camera, region, depth, colors, subpixels=2):
    """World points and colours of a view's ``region`` pixels (``depth`` along the rays, ``colors``
    (H, W, 3)), ``subpixels``^2 rays per pixel so that the points leave no gap between lattice vertices."""
    py, px = np.nonzero(region & np.isfinite(depth))
    offsets = (np.arange(subpixels) + 0.5) / subpixels
    ox, oy = np.meshgrid(offsets, offsets)
    sx = (px[:, None] + ox.reshape(1, -1)).reshape(-1)
    sy = (py[:, None] + oy.reshape(1, -1)).reshape(-1)
    o, d = pixel_rays(camera, sx, sy)
    t = np.repeat(depth[py, px], subpixels ** 2)
    return o + t[:, None] * d, np.repeat(colors[py, px], subpixels ** 2, axis=0)


def reference_views(ds, count, min_share=0.5):
    """Up to ``count`` training views to inpaint: the one with the largest mask, then in turn the view
    farthest from those already picked among the views whose mask is at least ``min_share`` of the
    largest (the object seen well from around it)."""
    train = list(ds.masked_train)
    area = np.array([ds.masks[v].sum() for v in train], np.float64)
    if not len(area) or not area.any():
        return []
    pool = [v for v, a in zip(train, area) if a >= min_share * area.max()]
    centre = {v: np.asarray(ds.cameras[v].to_world, np.float64)[:3, 3] for v in pool}
    picked = [train[int(np.argmax(area))]]
    while len(picked) < min(count, len(pool)):
        rest = [v for v in pool if v not in picked]
        picked.append(max(rest, key=lambda v: min(np.linalg.norm(centre[v] - centre[u]) for u in picked)))
    return picked


def lift_prior(inputs, state, allowed, views=4, fill="telea", dilation=0.01, tol=0.03, beyond=1.1):
    """For each of ``views`` reference views (:func:`reference_views`) in turn write the lifted 2D inpainting of its
    *hole* into ``state.fields['bg']`` (see the module docstring): the masked pixels (masks grown by
    ``dilation`` of the diagonal: edge pixels mix the object's colour in) where the background so far
    shows nothing (opacity below a half) or shows something ``beyond`` times farther than the surface
    around the mask continues (a way through the cleared hull). ``allowed(field)``: Float per stored
    vertex, > 0 where writing is allowed (the cleared hull). Returns a summary (per reference view its
    hole pixels, the fraction of them another view sees unmasked (:mod:`mi_voldis.fit.visibility`);
    the vertices written; the inpainter used) and their lattice keys."""
    ds = inputs.ds
    refs = reference_views(ds, views)
    if not refs:
        return {"reference_views": []}, np.zeros(0, np.int64)
    depth = training_depths(inputs, state, extra=refs)
    grow = diagonal_pixels(dilation, ds.size)
    written, holes, seen_share = [np.zeros(0, np.int64)], [], []
    for v in refs:
        region = dilate(ds.masks[v], grow)
        filled = fill_disparity(depth[v], region, camera=ds.cameras[v])
        rgb, alpha, bg_depth = render_camera(fit_integrator(inputs, state), ds.cameras[v], ("bg",))["bg"]
        hole = region & ((alpha < 0.5) | (bg_depth > beyond * filled))
        holes.append(int(hole.sum()))
        if not hole.any():
            seen_share.append(None)
            continue
        image = np.where((region & ~hole)[..., None], np.clip(rgb, 0, 1), ds.images[v])
        colors = inpainter(fill)(np.clip(image, 0, 1), hole)
        points, point_rgb = lift_pixels(ds.cameras[v], hole, filled, np.clip(colors, 0, 1))
        state.fields["bg"], keys = write_surface(state.fields["bg"], inputs.space, points, point_rgb, allowed)
        written.append(keys)
        others = [u for u in depth if u != v]
        seen = seen_elsewhere(pixel_points(ds.cameras[v], filled, np.flatnonzero(hole)),
                              [ds.cameras[u] for u in others], [depth[u] for u in others],
                              [ds.masks[u] for u in others], tol=tol)
        seen_share.append(float(seen.mean()))
    written = np.unique(np.concatenate(written))
    summary = {"reference_views": [int(v) for v in refs], "hole_pixels": holes, "seen_elsewhere": seen_share,
               "vertices_written": int(len(written)), "inpainter": inpainter_name(fill)}
    return summary, written
