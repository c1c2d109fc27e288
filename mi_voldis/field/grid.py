"""Dense voxel grids packed for fast trilinear lookup.

A grid of resolution (X, Y, Z) holds values at its vertices: vertex (i, j, k) sits at the local
position (i / (X-1), j / (Y-1), k / (Z-1)) of the unit cube, so the grid spans the cube exactly and
trilinear upsampling of a grid leaves its interpolant unchanged. Tensors use Mitsuba's volume
layout, shape (Z, Y, X, C) with x varying fastest.

For lookups, the channels of all of a field's tensors are interleaved per vertex and padded to a
power of two (``packet_width``): each of the 8 corners of a trilinear lookup is then a single
packet gather (faster in training than ``dr.Texture3f``, which pads and copies; reports/notes.md).
"""
import drjit as dr
import mitsuba as mi
import numpy as np


def packet_width(channels):
    """Smallest power of two >= ``channels``: the per-vertex stride of a packed grid."""
    width = 1
    while width < channels:
        width *= 2
    return width


def grid_shape(tensor):
    """(X, Y, Z) resolution of a (Z, Y, X, C) tensor."""
    z, y, x = tensor.shape[:3]
    return (x, y, z)


class _Pack(dr.CustomOp):
    """Channel interleaving as a custom op. Both directions are single gathers: the packed array
    reads every slot from its tensor (or 0 in the padding), and since packing is a permutation the
    adjoint reads every tensor element back from the packed gradient (Dr.Jit's generic adjoint of a
    scatter would be a scatter-add into zeroed gradients)."""

    def eval(self, tensors):
        self.shapes = [t.shape for t in tensors]
        self.width = packet_width(sum(s[3] for s in self.shapes))
        n = self.shapes[0][0] * self.shapes[0][1] * self.shapes[0][2]
        slot = dr.arange(mi.UInt32, n * self.width)
        vertex, channel = slot // self.width, slot % self.width
        packed = mi.Float(0.0)
        for offset, tensor in zip(self._offsets(), tensors):
            c = tensor.shape[3]
            mine = (channel >= offset) & (channel < offset + c)
            packed = dr.select(mine, dr.gather(mi.Float, tensor.array, vertex * c + channel - offset, mine), packed)
        return packed

    def _offsets(self):
        """Packed-vertex slot of every tensor's first channel."""
        return np.cumsum([0] + [s[3] for s in self.shapes])[:-1].tolist()

    def backward(self):
        self.set_grad_in("tensors", unpack(self.grad_out(), [s[3] for s in self.shapes], self.shapes[0][:3]))


def pack(tensors):
    """Interleave the channels of same-sized (Z, Y, X, C_k) tensors into one flat array.

    Vertex v's channels land at ``[v * W, v * W + sum C_k)`` with ``W = packet_width(sum C_k)``;
    the padding is zero. Differentiable: gradients of the result flow back to every tensor."""
    return dr.custom(_Pack, list(tensors))


def unpack(packed, channels, zyx):
    """Inverse of :func:`pack`: (Z, Y, X, C_k) tensors of ``channels`` = [C_k] from a packed array
    (one gather each; not differentiable)."""
    width = packet_width(sum(channels))
    out, offset = [], 0
    for c in channels:
        n = int(np.prod(zyx)) * c
        index = dr.arange(mi.UInt32, n)
        values = dr.gather(mi.Float, dr.detach(packed), (index // c) * width + index % c + offset)
        out.append(mi.TensorXf(values, (*zyx, c)))
        offset += c
    return out


def trilinear(data, shape, width, channels, p, active=True, offset=0):
    """Trilinear interpolation of a packed grid at local points ``p`` in [0, 1]^3.

    ``data``: flat array from :func:`pack` (the grid's vertices from vertex ``offset`` on); ``shape``:
    (X, Y, Z); ``width``: its packet width; ``channels``: how many leading channels to return. Points
    outside the cube are clamped to it (callers mask them). Returns a list of ``channels`` Float arrays.

        v(p) = sum_{corners c} prod_axis (f_axis if c_axis else 1 - f_axis) * V[i + c]
    with i = floor(p * (res - 1)) and f = p * (res - 1) - i."""
    sx, sy, sz = shape
    x = dr.clip(p, 0.0, 1.0) * mi.Vector3f(sx - 1, sy - 1, sz - 1)
    i = dr.minimum(mi.Vector3u(mi.Vector3i(x)), mi.Vector3u(sx - 2, sy - 2, sz - 2))
    f = x - mi.Vector3f(i)
    base = (i.z * sy + i.y) * sx + i.x + offset
    weights = ((1.0 - f.x, f.x), (1.0 - f.y, f.y), (1.0 - f.z, f.z))
    n = dr.width(base)
    out = [mi.Float(0.0) for _ in range(channels)]
    for dz in (0, 1):
        for dy in (0, 1):
            wzy = weights[2][dz] * weights[1][dy]
            for dx in (0, 1):
                corner = dr.gather(mi.ArrayXf, data, base + ((dz * sy + dy) * sx + dx), active,
                                   shape=(width, n))
                w = wzy * weights[0][dx]
                for k in range(channels):
                    out[k] = dr.fma(w, corner[k], out[k])
    return out


def dilate_cells(cells):
    """Boolean (Z, Y, X) grid grown by one cell in all 26 directions."""
    z, y, x = cells.shape
    padded = np.pad(cells, 1)
    out = np.zeros_like(cells)
    for dz in range(3):
        for dy in range(3):
            for dx in range(3):
                out |= padded[dz:dz + z, dy:dy + y, dx:dx + x]
    return out


def neighbour_indices(shape):
    """Flat indices of the 6 axis neighbours (-x, +x, -y, +y, -z, +z) of every element of a flat
    (Z, Y, X, C) array, same channel; an element on the border is its own neighbour there (Neumann)."""
    z, y, x, c = shape
    i = dr.arange(mi.UInt32, x * y * z * c)
    ch, v = i % c, i // c
    vx, vy, vz = v % x, (v // x) % y, v // (x * y)
    out = []
    for coord, size, stride in ((vx, x, 1), (vy, y, x), (vz, z, x * y)):
        for step in (-1, 1):
            ok = (coord > 0) if step < 0 else (coord + 1 < size)
            out.append(mi.UInt32(dr.select(ok, mi.Int32(v) + step * stride, mi.Int32(v))) * c + ch)
    return out
