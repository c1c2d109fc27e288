"""Ray intervals in boxes: the range [t_0, t_1] of a ray that the march samples.

The march (:mod:`mi_voldis.render.march`) samples t_i = t_0 + (i + u) dt, i = 0..N-1, over the union
[t_0, t_1] of the ray's intervals in all density-carrying boxes, with one jitter u in [0, 1) per ray.
Every field is evaluated at exactly these points (foreground fields at T^-1 of them), which is what
makes the per-sample differences of paper Eq. 3 meaningful.
"""
import drjit as dr
import mitsuba as mi

from ..transforms import apply_point, apply_vector


def unit_cube_interval(o, d):
    """[t_lo, t_hi] where o + t d lies in the unit cube (slab test); t_lo > t_hi when missed.

    Axes with d = 0 contribute (-inf, inf) when o is inside that slab and an empty interval
    otherwise, so rays parallel to a face (or grazing an edge) never produce NaN."""
    t_lo, t_hi = mi.Float(-dr.inf), mi.Float(dr.inf)
    for axis in range(3):
        oa, da = o[axis], d[axis]
        inv = dr.rcp(da)
        ta, tb = -oa * inv, (1.0 - oa) * inv
        parallel = da == 0.0
        inside = (oa >= 0.0) & (oa <= 1.0)
        lo = dr.select(parallel, dr.select(inside, -dr.inf, dr.inf), dr.minimum(ta, tb))
        hi = dr.select(parallel, dr.select(inside, dr.inf, -dr.inf), dr.maximum(ta, tb))
        t_lo, t_hi = dr.maximum(t_lo, lo), dr.minimum(t_hi, hi)
    return t_lo, t_hi


def sample_interval(boxes, o, d, t_min=0.0, t_max=dr.inf):
    """Union of the ray's intervals in ``boxes`` (world -> unit-cube matrices), clipped to
    [t_min, t_max]. Returns (t_0, t_1, hit); t_0 = t_1 = 0 where nothing is hit."""
    t0, t1 = mi.Float(dr.inf), mi.Float(-dr.inf)
    for to_local in boxes:
        lo, hi = unit_cube_interval(apply_point(to_local, o), apply_vector(to_local, d))
        hit = lo <= hi
        t0 = dr.select(hit, dr.minimum(t0, lo), t0)
        t1 = dr.select(hit, dr.maximum(t1, hi), t1)
    t0, t1 = dr.maximum(t0, t_min), dr.minimum(t1, t_max)
    hit = t0 < t1
    return dr.select(hit, t0, 0.0), dr.select(hit, t1, 0.0), hit
