"""Regularisers of fitting, as analytic gradients added to the optimised grids (no AD pass needed).

* total variation of a grid, TV(t) = sum_v sum_axis (t[v + e_axis] - t[v])^2 / n, per channel;
* sparsity, the L1 norm of activated density, sum_v softplus(D_v) / n.
"""
import drjit as dr
import mitsuba as mi

from .grid import neighbour_indices


def tv_gradient(tensor):
    """Gradient of TV(t) (module docstring) of a (Z, Y, X, C) tensor, every channel:
    2 (2 t[v] - t[v + e] - t[v - e]) summed over axes (Neumann border), divided by n = X Y Z C."""
    n = dr.width(tensor.array)
    t = tensor.array
    out = dr.zeros(mi.Float, n)
    centre = dr.gather(mi.Float, t, dr.arange(mi.UInt32, n))
    for j in neighbour_indices(tensor.shape):
        out += 2.0 * (centre - dr.gather(mi.Float, t, j))
    return out * (1.0 / n)


def sparsity_gradient(raw_density, weight):
    """Gradient of ``weight`` * sum_v softplus(D_v) with respect to raw densities D: weight sigmoid(D)."""
    return weight * dr.rcp(1.0 + dr.exp(-raw_density))
