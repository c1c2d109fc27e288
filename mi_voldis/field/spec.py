"""``radiance_field`` plugin dictionaries from NumPy arrays (for ``mi.load_dict``), and the colour channel
layouts the plugin reads."""
import mitsuba as mi
import numpy as np

from ..transforms import to_scalar_transform
from . import bricks
from .activations import inverse_softplus, logit

# Colour channels a vertex -> (spherical-harmonic degree, grey view dependence): the layouts the
# ``radiance_field`` plugin reads (its docstring has the colour model).
COLOR_LAYOUTS = {3: (0, False), 6: (1, True), 12: (1, False), 27: (2, False)}


def color_channels(degree, grey=False):
    """Raw colour channels of a field at spherical-harmonic ``degree``: an RGB triple for the mean colour and,
    for every higher harmonic, one grey coefficient (``grey``) or an RGB triple."""
    harmonics = (degree + 1) ** 2
    return 3 + (harmonics - 1) * (1 if grey else 3)


def box_transform(lo, hi):
    """4x4 matrix mapping the unit cube onto the axis-aligned box [lo, hi]."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    m = np.diag([*(hi - lo), 1.0])
    m[:3, 3] = lo
    return m


def field_dict(density, color, to_world=None, density_scale=1.0):
    """Plugin dict of a field with raw grids ``density`` (Z, Y, X[, 1]) and ``color`` (Z, Y, X, C)."""
    density = np.asarray(density, np.float32)
    if density.ndim == 3:
        density = density[..., None]
    out = {"type": "radiance_field", "density": mi.TensorXf(density),
           "color": mi.TensorXf(np.asarray(color, np.float32)), "density_scale": float(density_scale)}
    if to_world is not None:
        out["to_world"] = to_scalar_transform(to_world)
    return out


def brick_field_dict(density, color, to_world=None, density_scale=1.0, brick=8, keep=None):
    """Plugin dict of the same field stored as a brick grid (:mod:`mi_voldis.field.bricks`); ``keep``: the
    bricks to allocate (default: all)."""
    density = np.asarray(density, np.float32)
    values = np.concatenate([density.reshape(density.shape[:3] + (1,)), np.asarray(color, np.float32)], -1)
    layout, data = bricks.from_dense(values, brick, keep, width=values.shape[-1])
    out = {"type": "radiance_field", "table": mi.TensorXf(layout.table.ravel().astype(np.float32)),
           "data": mi.TensorXf(data.reshape(-1, values.shape[-1])[brick ** 3:]),
           "vertices": mi.ScalarVector3f(*layout.shape), "brick": brick, "density_scale": float(density_scale)}
    if to_world is not None:
        out["to_world"] = to_scalar_transform(to_world)
    return out


def constant_field(sigma, color, to_world=None, shape=(2, 2, 2)):
    """A homogeneous field: density ``sigma`` (per unit length) and RGB ``color`` everywhere in its box."""
    density = np.full(shape + (1,), inverse_softplus(sigma), np.float32)
    rgb = np.broadcast_to(logit(color), shape + (3,))
    return field_dict(density, rgb, to_world)
