"""Where the full field's rays end: the median point of each ray, and the weight in front of it.

The median point of a ray is where its transmittance T(t) = exp(-integral_0^t sigma) falls below a
half. Unlike the expected depth it is not pulled towards the camera or the far background by haze
and half-transparent voxels, so the surfaces of different views agree (masks, visibility, priors).
The weight a ray spends well in front of it, sum_i w_i [t_i < (1 - margin) t_med], is haze or
floaters: light the field explains with a semi-transparent veil instead of the surface, which both
fields share, so the foreground w_fg = w_full - w_bg behind it is that much fainter. Against a known
surface (a synthetic scene's ground truth) the weight splits by band of distance relative to it
(:func:`weight_bands`): how much of each ray's opacity the field puts on the surface, and how much in
front of it.
"""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..cameras import pixel_rays
from ..device import from_numpy
from . import march

CHUNK = 1 << 16  # rays per launch


def median_points(integrator, o, d, chunk=CHUNK, layer="full", level=0.5):
    """The median point of ``layer``'s field ('full' or 'bg') on each world ray (``o``, ``d`` (n, 3)):
    where its transmittance falls below a half (or ``level``), world space (n, 3), and whether it does (n,)
    bool."""
    plan = integrator.plan((layer,))
    chain = getattr(plan.sources, layer)
    points, hit = np.zeros((len(o), 3)), np.zeros(len(o), bool)
    with dr.suspend_grad():
        for s in range(0, len(o), chunk):
            n = min(chunk, len(o) - s)
            found = dr.zeros(mi.Float, 4 * n)
            index = dr.arange(mi.UInt32, n)

            def probe(p, w, active, depth):
                before = dr.exp(-depth[chain])
                cross = active & (before >= level) & (before - w[chain] < level)
                q = plan.space.to_world(p)
                for k, value in enumerate((q.x, q.y, q.z, mi.Float(1.0))):
                    dr.scatter(found, value, index * 4 + k, cross)

            rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o[s:s + n]), from_numpy(mi.Vector3f, d[s:s + n]))
            march.forward(plan, rays, dr.full(mi.Float, 0.5, n), probe=probe)
            f = np.array(found).reshape(n, 4)
            points[s:s + n], hit[s:s + n] = f[:, :3], f[:, 3] > 0
    return points, hit


def median_depth(integrator, camera, chunk=CHUNK, layer="full"):
    """The median depth of ``layer``'s field ('full' or 'bg') through ``camera``'s pixel centres
    (H, W): distance along each ray to its median point, 0 where it has none, and where it has one
    (H, W) bool."""
    o, d = _camera_rays(camera)
    points, hit = median_points(integrator, o, d, chunk, layer)
    depth = np.where(hit, np.linalg.norm(points - o, axis=1), 0.0)
    return depth.reshape(camera.height, camera.width), hit.reshape(camera.height, camera.width)


def front_weight(integrator, camera, margin=0.1, chunk=CHUNK, layer="full"):
    """Per pixel of ``camera`` (H, W): ``layer``'s field's ('full' or 'bg') weight on its ray more than
    ``margin`` times the median depth in front of its median point, sum_i w_i [t_i < (1 - margin) t_med]
    (module docstring), and whether the ray has a median point (H, W) bool (the weight is 0 where not)."""
    o, d = _camera_rays(camera)
    points, hit = median_points(integrator, o, d, chunk, layer)
    reach = np.where(hit, (1.0 - margin) * np.linalg.norm(points - o, axis=1), 0.0)
    plan = integrator.plan((layer,))
    chain = getattr(plan.sources, layer)
    out = np.zeros(len(o))
    with dr.suspend_grad():
        for s in range(0, len(o), chunk):
            n = min(chunk, len(o) - s)
            total = dr.zeros(mi.Float, n)
            index = dr.arange(mi.UInt32, n)
            origin, limit = from_numpy(mi.Point3f, o[s:s + n]), from_numpy(mi.Float, reach[s:s + n])

            def probe(p, w, active, _depth):
                front = active & (dr.norm(plan.space.to_world(p) - origin) < limit)
                dr.scatter_reduce(dr.ReduceOp.Add, total, w[chain], index, front)

            rays = march.prepare_rays(plan, origin, from_numpy(mi.Vector3f, d[s:s + n]))
            march.forward(plan, rays, dr.full(mi.Float, 0.5, n), probe=probe)
            out[s:s + n] = np.array(total)
    return out.reshape(camera.height, camera.width), hit.reshape(camera.height, camera.width)


def weight_bands(integrator, camera, reference, edges, chunk=CHUNK, layer="full"):
    """Per pixel of ``camera`` (H, W, len(``edges``) + 1): ``layer``'s field's ('full' or 'bg') weight on
    its ray by band of t / t_ref, t the sample's distance along the ray and t_ref the pixel's distance in
    ``reference`` (H, W; e.g. the true surface's): band k sums w_i over e_(k-1) <= t_i / t_ref < e_k, with
    e_(-1) = 0 and e_(len(edges)) = infinity (``edges`` increasing). Pixels whose reference is not finite
    and positive get zeros. The bands sum to the ray's opacity, 1 - T."""
    edges = np.asarray(edges, np.float64)
    o, d = _camera_rays(camera)
    ref = np.asarray(reference, np.float64).reshape(-1)
    valid = np.isfinite(ref) & (ref > 0)
    plan = integrator.plan((layer,))
    chain = getattr(plan.sources, layer)
    bands = len(edges) + 1
    out = np.zeros((len(o), bands))
    with dr.suspend_grad():
        for s in range(0, len(o), chunk):
            n = min(chunk, len(o) - s)
            total = dr.zeros(mi.Float, n * bands)
            index = dr.arange(mi.UInt32, n)
            origin = from_numpy(mi.Point3f, o[s:s + n])
            scale = from_numpy(mi.Float, np.where(valid[s:s + n], 1.0 / np.where(valid[s:s + n], ref[s:s + n], 1.0),
                                                  0.0))

            def probe(p, w, active, _depth):
                ratio = dr.norm(plan.space.to_world(p) - origin) * scale
                band = dr.zeros(mi.UInt32, dr.width(ratio))
                for e in edges:  # the number of edges at or below the ratio
                    band += dr.select(ratio >= float(e), 1, 0)
                dr.scatter_reduce(dr.ReduceOp.Add, total, w[chain], index * bands + band, active & (scale > 0))

            rays = march.prepare_rays(plan, origin, from_numpy(mi.Vector3f, d[s:s + n]))
            march.forward(plan, rays, dr.full(mi.Float, 0.5, n), probe=probe)
            out[s:s + n] = np.array(total).reshape(n, bands)
    return out.reshape(camera.height, camera.width, bands)


def _camera_rays(camera):
    py, px = np.mgrid[0:camera.height, 0:camera.width]
    return pixel_rays(camera, px.ravel() + 0.5, py.ravel() + 0.5)
