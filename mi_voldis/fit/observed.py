"""How many training views see each brick of a field, and the learning rates that follow (DVGO's
per-voxel learning rates).

A brick is *observed* by a training view when its centre projects into the view's image in front of the
camera (its frustum; occlusion is not tested). With ``lr_views`` p > 0 every vertex of a brick observed
by n views steps at min(1, n / n_ref)^p times the phase's learning rates, n_ref the ``lr_views_quantile``
quantile of the counts of the bricks some view observes (1: the most views any brick has). What few views see is
constrained along few directions: the density there can sit anywhere along their rays, which is where
floaters grow; at a lower rate the TV and sparsity priors hold it longer, while what many views see fits
at the full rate. Adam's step does not change with the scale of a gradient, so the scale multiplies the
step itself (:attr:`mi_voldis.optim.adam.Adam.scales`).
"""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..cameras import DevicePoints
from ..device import from_numpy


def brick_centres(field):
    """Scene-space centres (n, 3) of the allocated bricks of ``field`` (a FieldState), in slot order
    1..n: the middle of each brick's vertices that lie inside the lattice."""
    layout = field.layout
    b, top = layout.brick, np.array(layout.shape) - 1
    lo = layout.brick_coords() * b
    centre = (lo + np.minimum(lo + b - 1, top)) / 2.0
    local = centre / np.maximum(top, 1)
    m = field.to_world
    return local @ m[:3, :3].T + m[:3, 3]


def brick_views(space, field, cameras):
    """Per slot of ``field`` (NumPy, the empty slot 0 included as 0): how many of ``cameras`` have the
    brick's centre in their image, in front of them."""
    centres = brick_centres(field)
    counts = np.zeros(len(centres) + 1)
    if len(centres) == 0:
        return counts
    at, n = DevicePoints(space.to_world_np(centres)), dr.zeros(mi.Float, len(centres))
    for cam in cameras:
        _, ok = at.pixel_of(cam)
        n += dr.select(ok, 1.0, 0.0)
        dr.eval(n)
    counts[1:] = n.numpy()
    return counts


def view_rate_scale(space, field, cameras, power, quantile=1.0):
    """Float per packed value of ``field``: min(1, n / n_ref)^``power`` for the values of every vertex of
    a brick observed by n of ``cameras`` (:func:`brick_views`), n_ref the ``quantile`` of the counts of
    the bricks some camera observes (1: their largest); 0 for the empty brick and for bricks no camera
    observes; 1 for a view lattice's values."""
    counts = brick_views(space, field, cameras)
    seen = counts[1:][counts[1:] > 0]  # bricks outside every frustum (under the floor, behind the rig) step at 0
    ref = float(np.quantile(seen, quantile)) if len(seen) else 0.0
    scale = np.minimum(counts / ref, 1.0) ** power if ref > 0 else np.zeros_like(counts)
    scale[0] = 0.0
    per_slot = from_numpy(mi.Float, scale.astype(np.float32))
    per_brick = field.layout.vertices_per_brick * field.width
    values = dr.arange(mi.UInt32, dr.width(field.data))
    in_bricks = values < field.layout.slots * per_brick
    return dr.select(in_bricks, dr.gather(mi.Float, per_slot, values // per_brick, in_bricks), 1.0)
