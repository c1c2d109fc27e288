"""The values of a field while it is fitted or edited: raw grids and their box, made, resampled, re-degreed.

A field's state is a :class:`FieldState` of Dr.Jit tensors (raw density and colour) and a box (unit
cube -> scene space matrix). Resampling evaluates the trilinear interpolant of the old raw grids at
the new vertices, so a finer grid over the same box represents the same field.
"""
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from . import grid
from .activations import inverse_softplus
from .fieldspec import box_transform
from .transforms import to_scalar_transform

EMPTY_COLOR = -10.0  # raw colour of "black" (sigmoid(-10) = 4.5e-5)


@dataclass
class FieldState:
    density: mi.TensorXf   # (Z, Y, X, 1) raw density
    color: mi.TensorXf     # (Z, Y, X, 3 (l+1)^2) raw colour coefficients
    to_world: np.ndarray   # unit cube -> scene space
    density_scale: float = 1.0  # sigma = density_scale * softplus(raw)

    @property
    def shape(self):
        return grid.grid_shape(self.density)

    @property
    def sh_degree(self):
        return {3: 0, 12: 1, 27: 2}[self.color.shape[3]]

    def plugin(self):
        return {"type": "radiance_field", "density": self.density, "color": self.color,
                "density_scale": float(self.density_scale),
                "to_world": to_scalar_transform(self.to_world)}


def shape_for(lo, hi, resolution):
    """Vertices per axis (X, Y, Z): ``resolution`` along the longest side, cubic voxels."""
    size = np.asarray(hi, np.float64) - np.asarray(lo, np.float64)
    return tuple(int(max(2, round(resolution * s / size.max()))) for s in size)


def voxel_size(state):
    lo, hi = box_corners(state.to_world)
    return float(np.max((hi - lo) / (np.array(state.shape) - 1)))


def box_corners(to_world):
    return to_world[:3, 3].copy(), to_world[:3, 3] + np.diag(to_world)[:3]


def init_state(lo, hi, resolution, sh_degree, density_raw, density_scale):
    shape = shape_for(lo, hi, resolution)
    z, y, x = shape[::-1]
    density = dr.full(mi.TensorXf, density_raw, (z, y, x, 1))
    color = dr.zeros(mi.TensorXf, (z, y, x, 3 * (sh_degree + 1) ** 2))
    return FieldState(density, color, box_transform(lo, hi), density_scale)


def density_raw_for_alpha(alpha, step, density_scale):
    """Raw density whose opacity over a length ``step`` is ``alpha`` (DVGO's shifted activation)."""
    return float(inverse_softplus(-np.log1p(-alpha) / step / density_scale))


def vertex_positions(state):
    """Scene-space positions of the grid vertices, (n, 3) Dr.Jit point, x fastest."""
    sx, sy, sz = state.shape
    idx = dr.arange(mi.UInt32, sx * sy * sz)
    x, y, z = idx % sx, (idx // sx) % sy, idx // (sx * sy)
    local = mi.Point3f(mi.Float(x) / (sx - 1), mi.Float(y) / (sy - 1), mi.Float(z) / (sz - 1))
    m = state.to_world
    return mi.Point3f(*[float(m[r, 0]) * local.x + float(m[r, 1]) * local.y + float(m[r, 2]) * local.z
                        + float(m[r, 3]) for r in range(3)])


def resample(state, resolution=None, lo=None, hi=None, empty_raw=None):
    """The field on a new grid: ``resolution`` along the longest side of the box [lo, hi] (default:
    the current box). Points of the new box outside the old one get density ``empty_raw``."""
    old_lo, old_hi = box_corners(state.to_world)
    lo = old_lo if lo is None else np.asarray(lo, np.float64)
    hi = old_hi if hi is None else np.asarray(hi, np.float64)
    new = FieldState(None, None, box_transform(lo, hi), state.density_scale)
    shape = shape_for(lo, hi, resolution or max(state.shape))
    new.density = dr.zeros(mi.TensorXf, (shape[2], shape[1], shape[0], 1))  # for vertex_positions
    p = vertex_positions(new)
    inv = np.linalg.inv(state.to_world)
    local = mi.Point3f(*[float(inv[r, 0]) * p.x + float(inv[r, 1]) * p.y + float(inv[r, 2]) * p.z
                         + float(inv[r, 3]) for r in range(3)])
    packed = grid.pack([state.density, state.color])
    channels = 1 + state.color.shape[3]
    values = grid.trilinear(dr.detach(packed), state.shape, grid.packet_width(channels), channels, local)
    inside = dr.all((local >= -1e-6) & (local <= 1 + 1e-6))
    if empty_raw is not None:
        values[0] = dr.select(inside, values[0], empty_raw)
    z, y, x = shape[::-1]
    new.density = mi.TensorXf(values[0], (z, y, x, 1))
    color = dr.zeros(mi.Float, x * y * z * (channels - 1))
    idx = dr.arange(mi.UInt32, x * y * z)
    for k in range(1, channels):
        dr.scatter(color, values[k], idx * (channels - 1) + (k - 1))
    new.color = mi.TensorXf(color, (z, y, x, channels - 1))
    return new


def with_sh_degree(state, degree):
    """Colour coefficients truncated or zero-extended to ``degree`` (exact: see radiance_field)."""
    c = state.color.shape[3]
    want = 3 * (degree + 1) ** 2
    z, y, x = state.color.shape[:3]
    n = x * y * z
    out = dr.zeros(mi.Float, n * want)
    idx = dr.arange(mi.UInt32, n)
    for k in range(min(c, want)):
        dr.scatter(out, dr.gather(mi.Float, state.color.array, idx * c + k), idx * want + k)
    return FieldState(state.density, mi.TensorXf(out, (z, y, x, want)), state.to_world, state.density_scale)
