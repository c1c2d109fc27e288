"""The values of a field while it is fitted: a brick grid (:mod:`mi_voldis.field.bricks`) over an axis-aligned
box of scene space, made, carved, resampled onto finer lattices and re-degreed.

A :class:`FieldState` holds the lattice's :class:`~mi_voldis.field.bricks.Layout` and the packed vertex data
(density and colour coefficients interleaved per vertex, the empty brick first; then, for grey view
dependence on a lattice of its own, that lattice's vertices: ``radiance_field``'s ``view``) as one Dr.Jit
array: the very array the ``radiance_field`` plugin reads and Adam steps on. Resampling evaluates the
trilinear interpolant of the old grid at the new vertices, so a finer lattice over the same box represents
the same field; carving keeps only the bricks where some vertex has density (grown by a brick). The view
lattice keeps its resolution through both.
"""
import dataclasses
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from ..device import from_numpy
from ..transforms import to_scalar_transform
from . import bricks
from .activations import inverse_softplus
from .bricks import MEAN_CHANNELS
from .grid import packet_width
from .spec import COLOR_LAYOUTS, box_transform, color_channels

BRICK = 8  # vertices along a brick's edge


@dataclass
class FieldState:
    layout: bricks.Layout  # the lattice and its allocated bricks
    data: mi.Float         # packed values, (slots * B^3 + view vertices) x width floats, slot 0 the empty brick
    channels: int          # 1 + colour coefficients at a brick vertex (spec.color_channels)
    to_world: np.ndarray   # unit cube -> scene space (an axis-aligned box)
    density_scale: float = 1.0  # sigma = density_scale * softplus(raw)
    sh_gate: bool = False       # view dependence scaled by a voxel's opacity (radiance_field's sh_gate)
    view_shape: tuple | None = None  # (X, Y, Z) of the grey degree-1 view lattice after the bricks, or None

    @property
    def shape(self):
        return self.layout.shape

    def with_data(self, data, channels=None):
        """The same field (lattice, box, activation) over other packed values ``data`` (of ``channels``)."""
        return dataclasses.replace(self, data=data, channels=self.channels if channels is None else channels,
                                   to_world=self.to_world.copy())

    def bricks_data(self):
        """The bricks' packed values alone (the view lattice's rows left out)."""
        if self.view_shape is None:
            return self.data
        return dr.gather(mi.Float, self.data, dr.arange(mi.UInt32, self.vertices * self.width))

    def with_bricks(self, values):
        """The same field with the bricks' packed values ``values`` (the view lattice's kept)."""
        return self.with_data(_with_view_rows(values, self))

    @property
    def width(self):
        return packet_width(self.channels)

    @property
    def sh_degree(self):
        return 1 if self.view_shape is not None else COLOR_LAYOUTS[self.channels - 1][0]

    @property
    def grey(self):
        """View dependence by one grey coefficient a harmonic (not an RGB triple)."""
        return self.view_shape is not None or COLOR_LAYOUTS[self.channels - 1][1]

    @property
    def vertices(self):
        """Brick vertices stored (allocated bricks and the empty brick)."""
        return self.layout.slots * self.layout.vertices_per_brick

    @property
    def view_vertices(self):
        """Vertices of the view lattice (0 without one)."""
        return 0 if self.view_shape is None else int(np.prod(self.view_shape))

    def plugin(self):
        """``radiance_field`` plugin dict over these very values (no copy)."""
        view = {} if self.view_shape is None else {"view_vertices": mi.ScalarVector3f(*self.view_shape)}
        return {"type": "radiance_field", "table": mi.TensorXf(self.layout.table.ravel().astype(np.float32)),
                "data": mi.TensorXf(self.data, (self.vertices + self.view_vertices, self.width)),
                "channels": self.channels, **view,
                "vertices": mi.ScalarVector3f(*self.shape), "brick": self.layout.brick,
                "density_scale": float(self.density_scale), "sh_gate": bool(self.sh_gate),
                "to_world": to_scalar_transform(self.to_world)}

    def values(self):
        """The allocated bricks' values as NumPy (allocated * B^3, channels) (for files)."""
        v = np.array(self.data).reshape(-1, self.width)
        return v[self.layout.vertices_per_brick:self.vertices, :self.channels]

    def view_values(self):
        """The view lattice's coefficients as NumPy (Z, Y, X, 3) (for files), or None without one."""
        if self.view_shape is None:
            return None
        v = np.array(self.data).reshape(-1, self.width)[self.vertices:, 1:4]
        return v.reshape(*self.view_shape[::-1], 3)


def shape_for(lo, hi, resolution):
    """Vertices per axis (X, Y, Z): ``resolution`` along the longest side, cubic voxels."""
    size = np.asarray(hi, np.float64) - np.asarray(lo, np.float64)
    return tuple(int(max(2, round(resolution * s / size.max()))) for s in size)


def box_corners(to_world):
    return to_world[:3, 3].copy(), to_world[:3, 3] + np.diag(to_world)[:3]


def voxel_size(state):
    """Largest voxel edge (scene units)."""
    lo, hi = box_corners(state.to_world)
    return float(np.max((hi - lo) / (np.array(state.shape) - 1)))


def density_raw_for_alpha(alpha, step, density_scale):
    """Raw density whose opacity over a length ``step`` is ``alpha`` (DVGO's shifted activation)."""
    return float(inverse_softplus(-np.log1p(-alpha) / step / density_scale))


def new_field(lo, hi, resolution, sh_degree, density_raw, density_scale, brick=BRICK, grey=False, sh_gate=False,
              view_resolution=None):
    """A field over [lo, hi] with ``resolution`` vertices along its longest side, every brick
    allocated, raw density ``density_raw`` and raw colour 0 everywhere (colour of ``sh_degree``, with grey
    view dependence where ``grey``, on a view lattice of ``view_resolution`` vertices along the longest
    side where given, gated by opacity where ``sh_gate``)."""
    shape = shape_for(lo, hi, resolution)
    if sh_degree == 1 and grey and view_resolution:
        return with_sh_degree(new_field(lo, hi, resolution, 0, density_raw, density_scale, brick, sh_gate=sh_gate),
                              1, True, view_resolution)
    channels = 1 + color_channels(sh_degree, grey)
    bx, by, bz = bricks.counts(shape, brick)
    layout = bricks.Layout(shape, brick, np.arange(1, bx * by * bz + 1, dtype=np.uint32).reshape(bz, by, bx))
    width = packet_width(channels)
    vertex = np.zeros(width, np.float32)
    vertex[0] = density_raw
    values = np.tile(vertex, (layout.slots * brick ** 3, 1))
    values[: brick ** 3] = bricks.empty_values(width, channels)
    return FieldState(layout, from_numpy(mi.Float, values.ravel()), channels, box_transform(lo, hi), density_scale,
                      sh_gate)


def vertex_local(state):
    """Local (unit-cube) positions of every stored vertex (Dr.Jit Point3f, slot-major) and whether each
    is a lattice vertex of an allocated brick (Dr.Jit Bool)."""
    (i, j, k), inside = state.layout.device_coords()
    x, y, z = (float(s - 1) for s in state.shape)
    return mi.Point3f(mi.Float(i) / x, mi.Float(j) / y, mi.Float(k) / z), inside


def vertex_positions(state):
    """Scene-space positions of every stored vertex (NumPy (n, 3)) and whether each is a real one."""
    local, inside = vertex_local(state)
    local = np.array(local).T
    m = state.to_world
    return local @ m[:3, :3].T + m[:3, 3], np.array(inside)


def density_of(state):
    """Raw density of every stored vertex (NumPy)."""
    return np.array(dr.gather(mi.Float, state.data, dr.arange(mi.UInt32, state.vertices) * state.width))


def carve(state, needed):
    """The allocated bricks among ``needed`` (bz, by, bx bools), grown by one brick in every direction:
    what the field needs, with a brick of margin so that no surface blends with the empty brick."""
    return bricks.dilate_bricks(np.asarray(needed, bool) & (state.layout.table > 0)) & (state.layout.table > 0)


def resample(state, shape=None, keep=None):
    """The field on a lattice of ``shape`` vertices (default: the current one) over the same box, with
    the bricks ``keep`` of the old lattice (default: all allocated) and their images on the new one
    allocated; every new vertex holds the old field's trilinear interpolant there."""
    old = state.layout
    shape = tuple(shape or old.shape)
    keep = old.table > 0 if keep is None else keep
    new_keep = _bricks_over(keep, old, shape)
    table = np.zeros(new_keep.shape, np.uint32)
    table[new_keep] = np.arange(1, int(new_keep.sum()) + 1)
    layout = bricks.Layout(shape, old.brick, table)
    new = dataclasses.replace(state, layout=layout, data=None)
    local, real = vertex_local(new)
    values = bricks.trilinear(dr.detach(state.data), old, state.width, state.channels, local)
    width = state.width
    empty = bricks.empty_values(width, state.channels)
    data = dr.empty(mi.Float, new.vertices * width)
    idx = dr.arange(mi.UInt32, new.vertices)
    for c in range(width):
        v = values[c] if c < state.channels else mi.Float(0.0)
        dr.scatter(data, dr.select(real, v, float(empty[c])), idx * width + c)
    new.data = _with_view_rows(data, state)
    dr.eval(new.data)
    return new


def _with_view_rows(bricks_data, state, view=None):
    """Packed brick values ``bricks_data`` followed by the view lattice's rows: ``view`` (packed, that
    lattice's vertices x ``state.width``) or else ``state``'s own (none without a view lattice)."""
    if view is None:
        if state.view_shape is None:
            return bricks_data
        view = dr.gather(mi.Float, dr.detach(state.data),
                         dr.arange(mi.UInt32, state.view_vertices * state.width) + state.vertices * state.width)
    n = dr.width(bricks_data)
    out = dr.empty(mi.Float, n + dr.width(view))
    dr.scatter(out, bricks_data, dr.arange(mi.UInt32, n))
    dr.scatter(out, view, dr.arange(mi.UInt32, dr.width(view)) + n)
    return out


def resampled_vertices(state, shape, keep=None):
    """Stored vertices (the empty brick's included) of :func:`resample` (``state``, ``shape``, ``keep``),
    counted without allocating them."""
    keep = state.layout.table > 0 if keep is None else keep
    return (int(_bricks_over(keep, state.layout, tuple(shape)).sum()) + 1) * state.layout.vertices_per_brick


def _bricks_over(keep, old, shape):
    """Bricks of a lattice of ``shape`` vertices over the same box whose box overlaps a ``keep`` brick of
    the ``old`` layout."""
    b = old.brick
    counts = bricks.counts(shape, b)
    scale = (np.array(old.shape, np.float64) - 1) / (np.array(shape, np.float64) - 1)  # new -> old lattice
    out = np.zeros(counts[::-1], bool)
    z, y, x = np.nonzero(keep)
    if len(x) == 0:
        return out
    lo = np.stack([x, y, z], -1) * b                      # old lattice range [lo, lo + b) of each kept brick
    a = np.floor(lo / scale[None] / b).astype(int)        # the new bricks holding new vertices in it
    e = np.floor((np.ceil((lo + b) / scale[None]) - 1) / b).astype(int)
    a, e = np.clip(a, 0, np.array(counts) - 1), np.clip(e, 0, np.array(counts) - 1)
    for k in range(len(x)):
        out[a[k, 2]:e[k, 2] + 1, a[k, 1]:e[k, 1] + 1, a[k, 0]:e[k, 0] + 1] = True
    return out


def with_sh_degree(state, degree, grey=False, view_resolution=None):
    """Colour coefficients truncated or zero-extended to ``degree`` (exact: see radiance_field), with grey
    view dependence where ``grey``, on a view lattice of ``view_resolution`` vertices along the box's
    longest side where given (zero-extended too). Grey and RGB harmonics, and harmonics at the vertices
    and on a view lattice, are not each other's truncations: between them only through degree 0."""
    view = degree == 1 and grey and bool(view_resolution)
    if min(degree, state.sh_degree) > 0 and (grey != state.grey or view != (state.view_shape is not None)):
        raise ValueError("with_sh_degree: grey and RGB view dependence, or view dependence at the vertices and "
                         "on a view lattice, convert only through degree 0")
    if view and state.view_shape is not None:
        return state
    if state.view_shape is not None:  # to degree 0: the bricks alone
        state = dataclasses.replace(state, data=state.bricks_data(), view_shape=None, to_world=state.to_world.copy())
        return with_sh_degree(state, degree, grey)
    if view:
        base = with_sh_degree(state, 0)
        shape = shape_for(*box_corners(state.to_world), view_resolution)
        zeros = dr.zeros(mi.Float, int(np.prod(shape)) * base.width)
        return dataclasses.replace(base, data=_with_view_rows(base.data, base, zeros), view_shape=shape)
    channels = 1 + color_channels(degree, grey)
    width, old = packet_width(channels), state.width
    idx = dr.arange(mi.UInt32, state.vertices)
    data = dr.zeros(mi.Float, state.vertices * width)
    for c in range(min(channels, state.channels)):
        dr.scatter(data, dr.gather(mi.Float, state.data, idx * old + c), idx * width + c)
    b3 = state.layout.vertices_per_brick
    empty = bricks.empty_values(width, channels)
    for c in range(state.channels, channels):  # new coefficients of the empty brick stay empty
        dr.scatter(data, float(empty[c]), dr.arange(mi.UInt32, b3) * width + c)
    return state.with_data(data, channels)


def without_view_dependence(state, region):
    """``state`` with the view-dependent coefficients (every channel after the mean colour) of the vertices in
    ``region`` (Float or Bool per stored brick vertex) set to 0: there the colour is the mean, from every
    view. On a view lattice: the coefficients of the view vertices where the trilinear interpolant of
    ``region`` (1 inside, 0 outside and in unallocated bricks) is at least 1/2, i.e. the view vertices
    inside it to within half a brick voxel. A view cell is several brick voxels wide, so clearing every
    view vertex of a cell the region touches would also take the gloss off the surfaces around it, which
    a refit masked to the region never gives back."""
    if state.sh_degree == 0:
        return state
    if state.view_shape is not None:
        _, real = vertex_local(state)
        inside = dr.select(real & (mi.Float(region) > 0), 1.0, 0.0)
        sx, sy, sz = state.view_shape
        v = dr.arange(mi.UInt32, state.view_vertices)
        p = mi.Point3f(mi.Float(v % sx) / (sx - 1), mi.Float(v // sx % sy) / (sy - 1),
                       mi.Float(v // (sx * sy)) / (sz - 1))
        marked = bricks.trilinear(inside, state.layout, 1, 1, p)[0] >= 0.5
        view = dr.arange(mi.UInt32, state.view_vertices * state.width)
        old = dr.gather(mi.Float, state.data, view + state.vertices * state.width)
        cleared = dr.select(dr.gather(mi.Bool, marked, view // state.width), 0.0, old)
        return state.with_data(_with_view_rows(state.bricks_data(), state, cleared))
    i = dr.arange(mi.UInt32, dr.width(state.data))
    inside = mi.Bool(dr.gather(mi.Float, mi.Float(region), i // state.width) > 0)
    data = dr.select(inside & (i % state.width >= MEAN_CHANNELS), 0.0, state.data)
    return state.with_data(data)


def neighbour_vertices(state, evaluate=True):
    """For every stored vertex, the stored vertex index of its 6 axis neighbours (-x, +x, -y, +y, -z,
    +z) as UInt32 arrays; a vertex at the lattice border, of the empty brick or beyond the lattice is
    its own neighbour there (Neumann). Neighbours in unallocated bricks are empty-brick vertices.
    ``evaluate`` False: the tables as expressions, computed in whatever kernel reads them."""
    layout = state.layout
    coords, inside = layout.device_coords()
    own = dr.arange(mi.UInt32, state.vertices)
    out = []
    for axis in range(3):
        for step in (-1, 1):
            c = list(coords)
            ok = inside & ((c[axis] > 0) if step < 0 else (c[axis] + 1 < layout.shape[axis]))
            c[axis] = dr.select(ok, c[axis] + step if step > 0 else c[axis] - 1, c[axis])
            nb = dr.select(ok, layout.address(*c, ok), own)
            if evaluate:
                dr.eval(nb)
            out.append(nb)
    return out


def dilate_vertices(mask, neighbours, times=3):
    """A per-vertex Bool mask grown ``times`` times to the axis neighbours (``neighbour_vertices``);
    three times covers the 26 vertices that share a trilinear cell with a marked one."""
    for _ in range(times):
        grown = mi.Bool(mask)
        for nb in neighbours:
            grown |= dr.gather(mi.Bool, mask, nb)
        mask = grown
        dr.eval(mask)
    return mask
