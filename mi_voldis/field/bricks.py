"""Sparse brick grids: a vertex lattice stored only where the scene needs it.

A lattice of X x Y x Z vertices spans the unit cube as a dense grid does (:mod:`mi_voldis.field.grid`: vertex
(i, j, k) at (i / (X-1), j / (Y-1), k / (Z-1))), cut into bricks of B^3 vertices (B a power of two).
A *table* with one entry per brick gives the brick's *slot* in the data array; slot 0 is the empty
brick, shared by every brick that holds nothing: its vertices have raw density ``EMPTY_DENSITY`` and
raw colour ``EMPTY_COLOR`` (no density, black). The data array holds B^3 vertices per slot (x fastest
within a brick), each as ``width`` floats: the field's channels interleaved and padded to a power of
two, as :func:`mi_voldis.field.grid.pack` lays out a dense grid, so that a corner is one packet gather.

Trilinear interpolation reads each of the 8 corners through the table; where some corners lie in the
empty brick, it blends towards empty values. Fitting keeps allocated bricks one brick away from any
surface (:func:`dilate_bricks`), so surfaces never blend with the empty brick.

A dense grid is the special case with every brick allocated (:func:`from_dense`, :func:`to_dense`).
"""
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from ..device import from_numpy
from .grid import dilate_cells, packet_width

EMPTY_DENSITY = -20.0  # raw density of the empty brick: softplus(-20) = 2e-9
MEAN_CHANNELS = 4  # density and the mean colour's RGB: every colour layout's first four channels
EMPTY_COLOR = -10.0    # raw colour of "black" (sigmoid(-10) = 4.5e-5)


@dataclass
class Layout:
    """Where a brick grid's vertices live: ``shape`` (X, Y, Z) vertices, bricks of ``brick``^3
    vertices, ``table`` (bz, by, bx) uint32 slots (0: the empty brick)."""
    shape: tuple
    brick: int
    table: np.ndarray

    def __post_init__(self):
        b = self.brick
        if b < 2 or b & (b - 1):
            raise ValueError(f"brick size must be a power of two >= 2, got {b}")
        self.shape = tuple(int(s) for s in self.shape)
        if min(self.shape) < 2:
            raise ValueError(f"a grid needs at least 2 vertices per axis, got {self.shape}")
        want = tuple(counts(self.shape, b)[::-1])
        self.table = np.ascontiguousarray(self.table, np.uint32)
        if self.table.shape != want:
            raise ValueError(f"brick table must have shape {want} for {self.shape} vertices in bricks of "
                             f"{b}, got {self.table.shape}")
        self.slots = int(self.table.max(initial=0)) + 1
        used = np.sort(self.table[self.table > 0])
        if not np.array_equal(used, np.arange(1, self.slots)):
            raise ValueError("brick table must use each slot 1..n exactly once")
        self.shift = b.bit_length() - 1
        self.device_table = from_numpy(mi.UInt32, self.table.ravel())
        origins = np.concatenate([np.zeros((1, 3), np.int64), self.brick_coords()]) * b
        self.device_origins = [from_numpy(mi.UInt32, origins[:, a].astype(np.uint32)) for a in range(3)]

    @property
    def counts(self):
        """Bricks per axis (bx, by, bz)."""
        return self.table.shape[::-1]

    @property
    def vertices_per_brick(self):
        return self.brick ** 3

    @property
    def allocated(self):
        """Number of allocated bricks (the empty brick not counted)."""
        return self.slots - 1

    @property
    def occupied_fraction(self):
        return self.allocated / self.table.size

    def brick_coords(self):
        """(bx, by, bz) coordinates of the brick in each slot 1..n, as an (n, 3) int array in slot order."""
        z, y, x = np.nonzero(self.table)
        order = np.argsort(self.table[z, y, x])
        return np.stack([x[order], y[order], z[order]], axis=-1)

    def vertex_coords(self):
        """Lattice coordinates (i, j, k) of every vertex of every slot (the empty slot's included, as
        -1), NumPy (slots * B^3, 3), and whether each lies inside the lattice (bricks at the far
        borders may overhang it)."""
        b = self.brick
        local = np.stack(np.meshgrid(np.arange(b), np.arange(b), np.arange(b), indexing="ij")[::-1],
                         axis=-1).reshape(-1, 3)  # x fastest: (i, j, k) of local index
        origins = np.concatenate([np.full((1, 3), -10 ** 6), self.brick_coords() * b])
        coords = (origins[:, None, :] + local[None]).reshape(-1, 3)
        inside = np.all((coords >= 0) & (coords < np.array(self.shape)), axis=1)
        return coords, inside

    def device_coords(self):
        """Lattice coordinates (i, j, k) of every stored vertex (UInt32 arrays, slot-major) and whether
        each is a lattice vertex of an allocated brick (Bool), on the device."""
        s, m = self.shift, self.brick - 1
        v = dr.arange(mi.UInt32, self.slots * self.vertices_per_brick)
        slot = v >> (3 * s)
        i = dr.gather(mi.UInt32, self.device_origins[0], slot) + (v & m)
        j = dr.gather(mi.UInt32, self.device_origins[1], slot) + ((v >> s) & m)
        k = dr.gather(mi.UInt32, self.device_origins[2], slot) + ((v >> (2 * s)) & m)
        x, y, z = self.shape
        return (i, j, k), (slot > 0) & (i < x) & (j < y) & (k < z)

    def address(self, i, j, k, active=True):
        """Data vertex index of lattice vertex (i, j, k) (Dr.Jit UInt32 arrays, inside the lattice)."""
        s, m = self.shift, self.brick - 1
        bx, by, _ = self.counts
        slot = dr.gather(mi.UInt32, self.device_table, ((k >> s) * by + (j >> s)) * bx + (i >> s), active)
        return (slot << (3 * s)) | (((k & m) << (2 * s)) | ((j & m) << s) | (i & m))


def counts(shape, brick):
    """Bricks per axis needed to cover ``shape`` (X, Y, Z) vertices."""
    return tuple(-(-int(s) // brick) for s in shape)


def trilinear(data, layout, width, channels, p, active=True):
    """Trilinear interpolation of a brick grid at local points ``p`` in [0, 1]^3 (clamped to the cube;
    callers mask points outside). ``data``: the packed vertex values; returns ``channels`` Floats.
    The same interpolant as :func:`mi_voldis.field.grid.trilinear` of the dense grid it stores."""
    sx, sy, sz = layout.shape
    x = dr.clip(p, 0.0, 1.0) * mi.Vector3f(sx - 1, sy - 1, sz - 1)
    i = dr.minimum(mi.Vector3u(mi.Vector3i(x)), mi.Vector3u(sx - 2, sy - 2, sz - 2))
    f = x - mi.Vector3f(i)
    weights = ((1.0 - f.x, f.x), (1.0 - f.y, f.y), (1.0 - f.z, f.z))
    n = dr.width(i.x)
    out = [mi.Float(0.0) for _ in range(channels)]
    for dz in (0, 1):
        for dy in (0, 1):
            wzy = weights[2][dz] * weights[1][dy]
            for dx in (0, 1):
                v = layout.address(i.x + dx, i.y + dy, i.z + dz, active)
                corner = dr.gather(mi.ArrayXf, data, v, active, shape=(width, n))
                w = wzy * weights[0][dx]
                for c in range(channels):
                    out[c] = dr.fma(w, corner[c], out[c])
    return out


def empty_values(width, channels):
    """Packed values of one empty vertex: EMPTY_DENSITY, EMPTY_COLOR in the mean colour's channels, 0 in the
    view-dependent ones (black from every view) and in the padding."""
    mean = min(channels, MEAN_CHANNELS) - 1
    return np.array([EMPTY_DENSITY] + [EMPTY_COLOR] * mean + [0.0] * (width - 1 - mean), np.float32)


def from_dense(values, brick, keep=None, width=None):
    """Brick grid of a dense (Z, Y, X, C) NumPy array: (layout, packed data as NumPy (slots * B^3 * W,)).
    ``keep``: (bz, by, bx) bools, the bricks to allocate (default: all)."""
    values = np.asarray(values, np.float32)
    z, y, x, c = values.shape
    width = width or packet_width(c)
    bx, by, bz = counts((x, y, z), brick)
    keep = np.ones((bz, by, bx), bool) if keep is None else np.asarray(keep, bool)
    table = np.zeros((bz, by, bx), np.uint32)
    table[keep] = np.arange(1, int(keep.sum()) + 1)
    layout = Layout((x, y, z), brick, table)
    coords, inside = layout.vertex_coords()
    data = np.tile(empty_values(width, c), (layout.slots * brick ** 3, 1))
    ci = np.where(inside[:, None], coords, 0)
    data[inside, :c] = values[ci[inside, 2], ci[inside, 1], ci[inside, 0]]
    data[: brick ** 3] = empty_values(width, c)
    return layout, data.ravel()


def to_dense(data, layout, channels):
    """Dense (Z, Y, X, C) NumPy array of a brick grid (empty bricks as empty values)."""
    data = np.asarray(data, np.float32).reshape(layout.slots * layout.vertices_per_brick, -1)
    x, y, z = layout.shape
    out = np.empty((z, y, x, channels), np.float32)
    out[...] = empty_values(data.shape[1], channels)[:channels]
    coords, inside = layout.vertex_coords()
    c = coords[inside]
    out[c[:, 2], c[:, 1], c[:, 0]] = data[inside, :channels]
    return out


def dilate_bricks(keep, steps=1):
    """Brick mask grown by ``steps`` bricks in all 26 directions."""
    for _ in range(steps):
        keep = dilate_cells(keep)
    return keep
