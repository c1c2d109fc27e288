"""Regularisers of fitting, as analytic gradients added to the optimised grids (no AD pass needed).

On a field's packed values t (n stored values: the lattice's vertices x channels, see
:mod:`mi_voldis.field.state`; a view lattice's rows after them are no part of it):

* total variation, TV(t) = sum_v sum_axis (t[v + e_axis] - t[v])^2 / n, per channel;
* sparsity, the L1 norm of activated density, sum_v softplus(D_v).
"""
import drjit as dr
import mitsuba as mi

from .field.activations import sigmoid


def tv_gradient(values, width, neighbours, at=None):
    """Gradient of TV (module docstring) of packed ``values`` (``width`` floats per vertex) whose vertices
    have the axis ``neighbours`` (6 UInt32 arrays of vertex indices, Neumann border: a vertex is its own
    neighbour there): 2 (2 t[v] - t[v + e] - t[v - e]) summed over axes, divided by n; at the elements
    ``at`` (UInt32 indices into ``values``, in their order) where given, else at every element of the
    lattice's vertices (those ``neighbours`` covers)."""
    n = dr.width(neighbours[0]) * width
    if at is None and width % 4 == 0:
        return add_tv_gradient(dr.zeros(mi.Float, n), values, width, neighbours, [1.0] * width)
    i = dr.arange(mi.UInt32, n) if at is None else at
    vertex, channel = i // width, i % width
    centre = dr.gather(mi.Float, values, i)
    out = dr.zeros(mi.Float, dr.width(i))
    for nb in neighbours:
        out += 2.0 * (centre - dr.gather(mi.Float, values, dr.gather(mi.UInt32, nb, vertex) * width + channel))
    return out * (1.0 / n)


def add_tv_gradient(out, values, width, neighbours, weights):
    """``out`` (a Float as wide as ``values``) plus ``weights[c]`` times the TV gradient of channel c
    (:func:`tv_gradient`) at every element of the lattice's vertices, ``weights`` a number per slot of a
    vertex. Whole vertices are read in packets of 4 channels, each neighbour index once, and added into
    ``out`` in place where nothing else holds it (no array as wide as the grid for the TV alone)."""
    n = dr.width(neighbours[0]) * width
    if width % 4:
        i = dr.arange(mi.UInt32, n)
        tv = dr.gather(mi.Float, mi.Float(weights), i % width) * tv_gradient(values, width, neighbours, i)
        dr.scatter_add(out, tv, i)
        return out
    packets = width // 4
    vertex = dr.arange(mi.UInt32, n // width)
    others = [dr.gather(mi.UInt32, nb, vertex) * packets for nb in neighbours]
    for k in range(packets):
        centre = dr.gather(mi.Vector4f, values, vertex * packets + k)
        total = mi.Vector4f(0.0)
        for other in others:
            total += 2.0 * (centre - dr.gather(mi.Vector4f, values, other + k))
        scale = mi.Vector4f(*(float(w) / n for w in weights[4 * k:4 * k + 4]))
        dr.scatter_add(out, total * scale, vertex * packets + k)
    return out


def sparsity_gradient(raw_density, weight):
    """Gradient of ``weight`` * sum_v softplus(D_v) with respect to raw densities D: weight sigmoid(D)."""
    return weight * sigmoid(raw_density)
