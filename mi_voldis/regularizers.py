"""Regularisers of fitting, as analytic gradients added to the optimised grids (no AD pass needed).

On a field's packed values t (n stored values: vertices x channels, see :mod:`mi_voldis.field_state`):

* total variation, TV(t) = sum_v sum_axis (t[v + e_axis] - t[v])^2 / n, per channel;
* sparsity, the L1 norm of activated density, sum_v softplus(D_v).
"""
import drjit as dr
import mitsuba as mi

from .activations import sigmoid


def tv_gradient(values, width, neighbours, at=None):
    """Gradient of TV (module docstring) of packed ``values`` (``width`` floats per vertex) whose vertices
    have the axis ``neighbours`` (6 UInt32 arrays of vertex indices, Neumann border: a vertex is its own
    neighbour there): 2 (2 t[v] - t[v + e] - t[v - e]) summed over axes, divided by n; at the elements
    ``at`` (UInt32 indices into ``values``, in their order) where given, else at every element."""
    n = dr.width(values)
    if at is None and width % 4 == 0:  # whole vertices: each neighbour index read once, channels 4 at a time
        return _tv_packets(values, width, neighbours)
    i = dr.arange(mi.UInt32, n) if at is None else at
    vertex, channel = i // width, i % width
    centre = dr.gather(mi.Float, values, i)
    out = dr.zeros(mi.Float, dr.width(i))
    for nb in neighbours:
        out += 2.0 * (centre - dr.gather(mi.Float, values, dr.gather(mi.UInt32, nb, vertex) * width + channel))
    return out * (1.0 / n)


def _tv_packets(values, width, neighbours):
    """:func:`tv_gradient` at every element, in packets of 4 channels (the same sums in the same order)."""
    n, packets = dr.width(values), width // 4
    vertex = dr.arange(mi.UInt32, n // width)
    others = [dr.gather(mi.UInt32, nb, vertex) * packets for nb in neighbours]
    out = dr.zeros(mi.Float, n)
    for k in range(packets):
        centre = dr.gather(mi.Vector4f, values, vertex * packets + k)
        total = mi.Vector4f(0.0)
        for other in others:
            total += 2.0 * (centre - dr.gather(mi.Vector4f, values, other + k))
        dr.scatter(out, total * (1.0 / n), vertex * packets + k)
    return out


def sparsity_gradient(raw_density, weight):
    """Gradient of ``weight`` * sum_v softplus(D_v) with respect to raw densities D: weight sigmoid(D)."""
    return weight * sigmoid(raw_density)
