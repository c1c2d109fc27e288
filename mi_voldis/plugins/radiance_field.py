"""The ``radiance_field`` medium plugin: a voxel-grid radiance field over a box."""
from __future__ import annotations

import zipfile

import drjit as dr
import mitsuba as mi
import numpy as np

from ..field import bricks, grid
from ..field.activations import one_minus_exp, sigmoid, softplus
from ..field.spec import COLOR_LAYOUTS
from ..io.vol import grid_values, read_header, read_vol
from ..transforms import to_matrix

__variant__ = mi.variant()

# colour channels -> (spherical-harmonic degree, grey): RGB; degree 1 with one grey coefficient a harmonic;
# degree 1 / 2 with an RGB triple a harmonic
SH_Y0 = 0.28209479177387814  # Y_0^0 = 1 / (2 sqrt(pi))


def _unpacked_tensor(slot, doc):
    """A tensor attribute of :class:`RadianceField` that is unpacked from ``packed`` when it is stale."""
    def get(self):
        self._unpack()
        return getattr(self, slot)

    def set(self, value):
        self._unpack()  # the other tensor must not go stale
        setattr(self, slot, value)
    return property(get, set, doc=doc)


class RadianceField(mi.Medium):
    r"""
    .. _medium-radiance_field:

    Radiance field (:monosp:`radiance_field`)
    -----------------------------------------

    .. pluginparameters::

     * - density
       - |string|, |tensor| or |volumegrid|
       - Raw (pre-activation) density at the grid vertices: a ``.vol`` file with one channel, a
         ``mi.TensorXf`` of shape (Z, Y, X, 1) or a ``mi.VolumeGrid``. (Required)
       - |exposed|, |differentiable|

     * - color
       - |string|, |tensor| or |volumegrid|
       - Raw colour at the same vertices: 3 channels (RGB); 12 / 27 channels for spherical
         harmonics of degree 1 / 2, ordered basis-major (channel 3 k + rgb); or 6 channels for degree 1
         with grey view dependence (RGB of the mean, then one coefficient for each of Y_1^-1, Y_1^0,
         Y_1^1, added to R, G and B alike). (Required)
       - |exposed|, |differentiable|

     * - grid
       - |string|
       - Instead of ``density`` and ``color``: a sparse brick grid (:mod:`mi_voldis.field.bricks`), a
         ``.npz`` file with ``table`` (bz, by, bx) brick slots, ``data`` (allocated bricks, B^3
         vertices, 1 + colour channels) raw values, ``vertices`` (X, Y, Z) and ``bbox`` (the box, as
         a ``.vol`` header has it). In memory: the tensors ``table`` and ``data`` and the vector
         ``vertices``. |exposed| ``data``, |differentiable| (the packed values, empty brick first).

     * - view
       - |tensor|
       - With a brick grid of RGB colour: grey degree-1 view dependence on a dense lattice of its own over
         the same box, a tensor (Z', Y', X', 3) of the coefficients of Y_1^-1, Y_1^0 and Y_1^1 (in a grid
         file its array ``view``; with the packed ``data`` of a field state, ``view_vertices`` (X', Y', Z')
         and the lattice's vertices after the bricks'). The field is then of degree 1, grey (below).
         (Default: none)
       - |exposed|, |differentiable| (in ``data``)

     * - to_world
       - |transform|
       - Maps the unit cube [0, 1]^3 onto the field's box. (Default: the bounding box stored in the
         density ``.vol`` header or the grid file; the unit cube for tensors)

     * - density_scale
       - |float|
       - s in sigma = s softplus(D): fitting sets it to one over a voxel's size so that raw values
         are densities per voxel, as DVGO does (a surface is then opaque at raw ~ 10, a value Adam
         reaches in tens of steps, instead of ~ 10 / voxel). (Default: 1)

     * - sh_gate
       - |bool|
       - View dependence in proportion to opacity: the harmonics' terms scaled by the opacity g of the
         density over one voxel (below). Faint density then shows its mean colour from every side, so a
         fit cannot explain a view-dependent look with a haze of view-coloured density. (Default: false)

    The field answers only one question, density and colour at points:

    .. math::

        \sigma(p) = s \, \mathrm{softplus}(D(p)), \qquad
        c(p, d) = \mathrm{sigmoid}\Big(C_0(p) + \sum_{k \ge 1} \frac{Y_k(d)}{Y_0} C_k(p)\Big)

    where D and C_k are trilinear interpolants of the raw grids (activation after interpolation, as
    DVGO does, which gives sharp surfaces from coarse grids), Y_k are real spherical harmonics and d is
    the direction of travel. softplus keeps a gradient everywhere (no dead cells at initialisation);
    densities are per unit of world length. Outside the box the density is 0. Dividing by Y_0 makes
    C_0 the logit of the mean colour at every degree, so raising a field's degree by appending zero
    coefficients does not change it. With grey view dependence (6 colour channels) every C_k, k >= 1,
    is one scalar added to all three logits: a gloss that brightens or darkens a surface with the view
    (a varnished top that mirrors the sky) at half a degree-1 vertex's memory (8 floats against 16).

    With a ``view`` lattice the gloss coefficients are not stored at the brick vertices but on a dense
    lattice of their own, C_k(p) = V_k(p), k = 1..3, the trilinear interpolant of the view lattice at p. A
    gloss varies slowly in space (it follows the light and the material, not the texture), so a lattice
    of 64^3 carries it (measured in ``reports/notes.md``) while the bricks, which carry density and the
    mean colour at the finest pitch, keep degree 0's 4 floats a vertex. Packed, a view vertex sits after
    the bricks' vertices with its three coefficients where a brick vertex has its RGB (the density slot
    unused, 0).

    With ``sh_gate`` every term k >= 1 is scaled by g(p) = 1 - exp(-sigma(p) h), the opacity of the
    density over the grid's largest voxel edge h: 1 on a surface, sigma h on a haze that light crosses.
    No gradient flows to the density through g (it is held constant in the derivative): a faint voxel
    would otherwise be pushed to grow opaque to buy view dependence.

    The grid's vertex (i, j, k) sits at local position (i/(X-1), j/(Y-1), k/(Z-1)); the tensors are
    ``mi.VolumeGrid``-ordered (Z, Y, X, C). The ``voldis`` integrator evaluates this medium; Mitsuba's
    path tracers cannot (it has no scattering).

    .. tabs::

        .. code-tab:: xml

            <medium type="radiance_field" name="full">
                <string name="density" value="full_density.vol"/>
                <string name="color" value="full_color.vol"/>
                <transform name="to_world"> <scale value="2"/> <translate value="-1, -1, -1"/> </transform>
            </medium>

        .. code-tab:: python

            'full': {'type': 'radiance_field', 'density': mi.TensorXf(d), 'color': mi.TensorXf(c)}
    """

    def __init__(self, props):
        super().__init__(props)
        name = props.id() or "radiance_field"
        self.layout, self.view_shape = None, None
        # whether lookups read the view lattice; fitting turns it off while the lattice is all 0 (before
        # progressive view dependence's onset): the same values without the lattice's 8 gathers and scatters
        self.view_enabled = True
        if "grid" in props or "table" in props:
            self.layout, self._data, self.channels, bbox, self.view_shape = _load_bricks(props, name)
            self._check_channels(self.channels - 1)
            if self.view_shape is not None and self.channels != 4:
                raise ValueError(f"{name}: a view lattice needs RGB colour at the brick vertices (3 channels), "
                                 f"got {self.channels - 1}")
            self._density = self._color = None
        else:
            if "view" in props or "view_vertices" in props:
                raise ValueError(f"{name}: a view lattice needs a brick grid ('grid' or 'table'), not dense "
                                 f"'density' and 'color'")
            density, bbox = _load_grid(props, "density", name)
            color, _ = _load_grid(props, "color", name)
            self._density, self._color = density, color
        if "to_world" in props:
            self.to_world = to_matrix(props.get("to_world"))
        elif bbox is not None:
            lo, hi = bbox
            self.to_world = np.diag([*(hi - lo), 1.0])
            self.to_world[:3, 3] = lo
        else:
            self.to_world = np.eye(4)
        if abs(np.linalg.det(self.to_world[:3, :3])) < 1e-12:
            raise ValueError(f"{name}: to_world must map the unit cube to a box of non-zero volume")
        self.world_to_local = np.linalg.inv(self.to_world)
        self.density_scale = float(props.get("density_scale", 1.0))
        if not self.density_scale > 0:
            raise ValueError(f"{name}: density_scale must be positive, got {self.density_scale}")
        self.sh_gate = props.get("sh_gate", False)
        if not isinstance(self.sh_gate, bool):
            raise ValueError(f"{name}: sh_gate must be a boolean, got {self.sh_gate!r}")
        self._packed = None
        self.parameters_changed()

    # ---------------------------------------------------------------- Mitsuba object protocol
    def traverse(self, callback):
        if self.layout is not None:
            callback.put("data", self._data, mi.ParamFlags.Differentiable)
            return
        callback.put("density", self.density, mi.ParamFlags.Differentiable)
        callback.put("color", self.color, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys=None):
        if self.layout is not None:
            data = self._data
            rows, width = self.rows, grid.packet_width(self.channels)
            if tuple(data.shape) != (rows, width):
                raise ValueError(f"radiance_field: brick data must have shape ({rows}, {width}), got "
                                 f"{tuple(data.shape)}")
            self.shape, self.width, self._packed = self.layout.shape, width, data.array
            return
        d, c = self.density, self.color
        if len(d.shape) != 4 or d.shape[3] != 1:
            raise ValueError(f"radiance_field: density must have shape (Z, Y, X, 1), got {tuple(d.shape)}")
        if len(c.shape) != 4 or tuple(c.shape[:3]) != tuple(d.shape[:3]):
            raise ValueError(f"radiance_field: color must have shape {tuple(d.shape[:3])} + (C,), "
                             f"got {tuple(c.shape)}")
        self._check_channels(c.shape[3])
        if min(d.shape[:3]) < 2:
            raise ValueError(f"radiance_field: the grid needs at least 2 vertices per axis, got "
                             f"{grid.grid_shape(d)}")
        self.shape = grid.grid_shape(d)
        self.channels = 1 + c.shape[3]
        self.width = grid.packet_width(self.channels)
        self._packed = None  # packed on first use: a step that sets both tensors packs them once

    def _check_channels(self, colour):
        if colour not in COLOR_LAYOUTS:
            raise ValueError(f"radiance_field: color needs 3, 6, 12 or 27 channels (RGB, SH degree 1 grey, "
                             f"SH degree 1/2), got {colour}")
        self.sh_degree, self.grey = (1, True) if self.view_shape is not None else COLOR_LAYOUTS[colour]

    @property
    def rows(self):
        """Packed vertices: the bricks' (empty brick first), then the view lattice's."""
        bricks_rows = self.layout.slots * self.layout.vertices_per_brick
        return bricks_rows + (0 if self.view_shape is None else int(np.prod(self.view_shape)))

    @property
    def lookup_channels(self):
        """Values :meth:`lookup` returns: density, the colour coefficients and the view lattice's three."""
        return self.channels + (0 if self.view_shape is None else 3)

    # ------------------------------------------------------------ values: tensors or packed
    density = _unpacked_tensor("_density", "Raw density tensor (Z, Y, X, 1).")
    color = _unpacked_tensor("_color", "Raw colour tensor (Z, Y, X, C).")

    @property
    def packed(self):
        """Density and colour interleaved per vertex (:func:`mi_voldis.field.grid.pack`; for a brick grid its
        data, empty brick first): what lookups read."""
        if self._packed is None:
            with dr.resume_grad():  # first read may happen where gradients are suspended (mi.render's primal)
                self._packed = grid.pack([self._density, self._color])
            dr.eval(self._packed)
        return self._packed

    def set_packed(self, packed):
        """Make ``packed`` (the layout of :attr:`packed`, same grid and channels) the field's values.

        Fitting optimises this array directly, so that a step neither packs the two tensors nor
        unpacks their gradients; ``density`` and ``color`` are unpacked from it when next read."""
        vertices = self.rows if self.layout is not None else self.shape[0] * self.shape[1] * self.shape[2]
        expected = vertices * self.width
        if dr.width(packed) != expected:
            raise ValueError(f"radiance_field: packed grid needs {expected} values, got {dr.width(packed)}")
        if self.layout is not None:
            self._data = mi.TensorXf(packed, (vertices, self.width))
            self._packed = packed
            return
        self._packed, self._density, self._color = packed, None, None

    def _unpack(self):
        if self.layout is not None:
            raise ValueError("radiance_field: a brick grid has no dense density and color tensors (see "
                             "mi_voldis.field.bricks.to_dense)")
        if self._density is None:
            self._density, self._color = grid.unpack(self._packed, [1, self.channels - 1],
                                                     self.shape[::-1])

    @property
    def voxel(self):
        """The grid's largest voxel edge, in the units of the box ``to_world`` maps onto."""
        return float(np.max(np.linalg.norm(self.to_world[:3, :3], axis=0) / (np.array(self.shape) - 1)))

    def to_string(self):
        kind = f"bricks={self.layout.allocated}/{self.layout.table.size}, " if self.layout is not None else ""
        if self.view_shape is not None:
            kind += f"view={self.view_shape}, "
        return (f"RadianceField[shape={self.shape}, {kind}sh_degree={self.sh_degree}, "
                f"density_scale={self.density_scale}, sh_gate={self.sh_gate}, to_world={self.to_world.tolist()}]")

    # -------------------------------------------------------------------- field evaluation
    def eval_local(self, p, d, data=None, active=True):
        """Density and colour at local points ``p`` (unit-cube coordinates), seen along ``d``.

        ``data`` is the packed grid to read (default: this field's own ``packed`` array; the
        integrator passes gradient-tracked copies during its adjoint pass). Returns
        ``(sigma, color)``; sigma is 0 outside the unit cube."""
        inside = dr.all((p >= 0.0) & (p <= 1.0)) & active
        return self.activate(self.lookup(p, data, inside), d, inside)

    def lookup(self, p, data=None, active=True):
        """Raw values at local points ``p`` (clamped to the unit cube): the ``lookup_channels``
        interpolated grid channels, density first (Float arrays)."""
        data = self.packed if data is None else data
        if self.layout is not None:
            out = bricks.trilinear(data, self.layout, self.width, self.channels, p, active)
            if self.view_shape is not None and self.view_enabled:  # the gloss, in the view vertices' RGB slots
                offset = self.layout.slots * self.layout.vertices_per_brick
                out += grid.trilinear(data, self.view_shape, self.width, 4, p, active, offset)[1:]
            elif self.view_shape is not None:
                out += [dr.zeros(mi.Float, dr.width(p)) for _ in range(3)]
            return out
        return grid.trilinear(data, self.shape, self.width, self.channels, p, active)

    def density_points(self, raw_threshold):
        """Local positions (Dr.Jit Point3f) of the vertices whose raw density exceeds ``raw_threshold``."""
        if self.layout is not None:
            (i, j, k), inside = self.layout.device_coords()
            raw = dr.gather(mi.Float, self.packed, dr.arange(mi.UInt32, dr.width(i)) * self.width)
        else:
            raw = dr.gather(mi.Float, self.packed, dr.arange(mi.UInt32, int(np.prod(self.shape))) * self.width)
            v = dr.arange(mi.UInt32, dr.width(raw))
            i, j, k = v % self.shape[0], (v // self.shape[0]) % self.shape[1], v // (self.shape[0] * self.shape[1])
            inside = mi.Bool(True)
        keep = dr.compress(inside & (raw > raw_threshold))
        if dr.width(keep) == 0:
            return dr.zeros(mi.Point3f, 0)
        x, y, z = (float(s - 1) for s in self.shape)
        return mi.Point3f(mi.Float(dr.gather(mi.UInt32, i, keep)) / x, mi.Float(dr.gather(mi.UInt32, j, keep)) / y,
                          mi.Float(dr.gather(mi.UInt32, k, keep)) / z)

    def density_vertices(self, raw_threshold):
        """Local positions (n, 3) (NumPy) of the vertices whose raw density exceeds ``raw_threshold``."""
        if self.layout is not None:
            (i, j, k), inside = self.layout.device_coords()
            raw = dr.gather(mi.Float, self.packed, dr.arange(mi.UInt32, dr.width(i)) * self.width)
            keep = dr.compress(inside & (raw > raw_threshold))
            coords = np.stack([np.array(dr.gather(mi.UInt32, c, keep)) for c in (i, j, k)], -1)
            return coords / (np.array(self.shape, np.float64) - 1)
        z, y, x = np.nonzero(np.array(self.density, np.float32)[..., 0] > raw_threshold)
        return np.stack([x, y, z], -1) / (np.array(self.shape, np.float64) - 1)

    def activate(self, v, d, active=True):
        """``(sigma, color)`` from raw values ``v`` (:meth:`lookup`) seen along ``d``: sigma =
        s softplus(v_0) where ``active`` (0 elsewhere), colour = sigmoid of the SH sum."""
        sigma = dr.select(active, self.density_scale * softplus(v[0]), 0.0)
        logits = [v[1], v[2], v[3]]
        if self.sh_degree > 0:
            basis = dr.sh_eval(dr.normalize(d), self.sh_degree)
            # the gate g = 1 - exp(-sigma h) = 1 - exp(-softplus(D) s h), constant in the derivative
            gate = dr.detach(one_minus_exp(softplus(v[0]) * (self.density_scale * self.voxel))) if self.sh_gate \
                else 1.0
            if self.grey:  # one coefficient a harmonic, the same for R, G and B
                gloss = mi.Float(0.0)
                for k in range(1, len(basis)):
                    gloss = dr.fma(basis[k] * (1.0 / SH_Y0), v[3 + k], gloss)
                logits = [c + gate * gloss for c in logits]
            else:
                for k in range(1, len(basis)):
                    scale = gate * basis[k] * (1.0 / SH_Y0)
                    for ch in range(3):
                        logits[ch] = dr.fma(scale, v[1 + 3 * k + ch], logits[ch])
        return sigma, mi.Color3f(sigmoid(logits[0]), sigmoid(logits[1]), sigmoid(logits[2]))

    # ------------------------------------------------ Mitsuba's path tracers: an empty medium
    # The field emits and absorbs; it does not scatter, so it is evaluated by the ``voldis`` integrator
    # only. Dr.Jit traces a virtual call through every live instance of a domain, so Mitsuba's
    # ``volpath`` traces these methods whenever a field exists in the process, even for scenes that do
    # not hold one: they answer "nothing here" instead of failing.
    def intersect_aabb(self, ray):
        return mi.Bool(False), mi.Float(dr.inf), mi.Float(dr.inf)

    def get_majorant(self, mei, active=True):
        return mi.Color3f(0.0)

    def get_scattering_coefficients(self, mei, active=True):
        return mi.Color3f(0.0), mi.Color3f(0.0), mi.Color3f(0.0)

    def sample_interaction(self, ray, sample, channel, active):
        mei = dr.zeros(mi.MediumInteraction3f, dr.width(sample))
        mei.t = mi.Float(dr.inf)
        return mei


def _load_grid(props, key, name):
    """Tensor of property ``key`` (file name, tensor or VolumeGrid) and the file's bbox (or None)."""
    if key not in props:
        raise ValueError(f"{name}: radiance_field needs a '{key}' property (.vol file or tensor)")
    value = props.get(key)
    bbox, source = None, name
    if isinstance(value, str):
        path = str(mi.file_resolver().resolve(value))
        header = read_header(path)
        bbox = _checked_box(path, header[4], header[5])
        value, source = read_vol(path), path
    elif isinstance(value, mi.VolumeGrid):
        value = grid_values(value)
    elif not isinstance(value, mi.TensorXf):
        raise ValueError(f"{name}: '{key}' must be a .vol file name, mi.TensorXf or mi.VolumeGrid, "
                         f"got {type(value).__name__}")
    tensor = mi.TensorXf(value)
    if not dr.all(dr.isfinite(tensor.array)):
        raise ValueError(f"{source}: '{key}' of field {name} contains NaN or Inf values")
    return tensor, bbox


def _checked_box(path, lo, hi):
    """(lo, hi) of a grid file's box; a box inverted, flat or not finite on any axis is refused naming
    the file (the field would be mirrored or collapsed without a word)."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(lo < hi)):
        raise ValueError(f"{path}: the grid's box needs min < max on every axis, got min "
                         f"[{', '.join(f'{v:g}' for v in lo)}] and max [{', '.join(f'{v:g}' for v in hi)}]")
    return lo, hi


mi.register_medium("radiance_field", lambda props: RadianceField(props))


def _load_bricks(props, name):
    """(Layout, packed data tensor (slots * B^3 + view vertices, width) with the empty brick first,
    channels, bbox or None, view lattice's (X, Y, Z) or None) of a brick grid given as a ``grid`` file
    or as ``table`` / ``data`` / ``vertices`` / ``brick`` (/ ``view``) properties (``data`` either the
    allocated bricks' values, or with ``channels`` (and ``view_vertices``) the packed array itself,
    empty brick included, as a field state holds it)."""
    bbox, view = None, None
    if "grid" in props:
        path = str(mi.file_resolver().resolve(props.get("grid")))
        try:
            with np.load(path) as f:
                table, data, vertices, brick = f["table"], f["data"], f["vertices"], int(f["brick"])
                bbox = np.asarray(f["bbox"], np.float64) if "bbox" in f.files else None
                view = np.asarray(f["view"], np.float32) if "view" in f.files else None
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as e:
            raise ValueError(f"{path}: not a brick grid file ({e})") from None
        if bbox is not None:
            if bbox.shape != (2, 3):
                raise ValueError(f"{path}: bbox must be [[x0, y0, z0], [x1, y1, z1]], got shape {bbox.shape}")
            bbox = _checked_box(path, *bbox)
    else:
        for key in ("table", "data", "vertices", "brick"):
            if key not in props:
                raise ValueError(f"{name}: a brick grid needs 'table', 'data', 'vertices' and 'brick'")
        table, data = np.array(props.get("table")), props.get("data")
        vertices, brick = np.array(props.get("vertices"), np.float64), int(props.get("brick"))
        view = np.array(props.get("view"), np.float32) if "view" in props else None
        path = name
    shape = tuple(int(v) for v in np.ravel(vertices))
    if len(shape) != 3:
        raise ValueError(f"{path}: a brick grid needs vertices (X, Y, Z), got {shape}")
    try:
        layout = bricks.Layout(shape, brick, np.asarray(table).astype(np.uint32).reshape(
            bricks.counts(shape, brick)[::-1]))
    except ValueError as e:
        raise ValueError(f"{path}: {e}") from None
    b3 = brick ** 3
    rows, cols = tuple(data.shape) if len(data.shape) == 2 else (-1, -1)
    view_shape = _view_shape(path, props, view)
    view_rows = 0 if view_shape is None else int(np.prod(view_shape))
    if "channels" in props and rows == layout.slots * b3 + view_rows and \
            cols == grid.packet_width(int(props.get("channels"))):
        if not dr.all(dr.isfinite(data.array)):
            raise ValueError(f"{path}: brick data contains NaN or Inf values")
        return layout, data, int(props.get("channels")), bbox, view_shape  # the packed array itself
    if rows != layout.allocated * b3 or cols < 4:
        raise ValueError(f"{path}: brick data must hold {layout.allocated} bricks of {b3} vertices x channels, "
                         f"got shape {tuple(data.shape)}")
    data = np.asarray(data, np.float32)
    if not np.all(np.isfinite(data)):
        raise ValueError(f"{path}: brick data contains NaN or Inf values")
    width = grid.packet_width(cols)
    values = np.zeros((layout.slots * b3 + view_rows, width), np.float32)
    values[:b3] = bricks.empty_values(width, cols)
    values[b3:layout.slots * b3, :cols] = data
    if view is not None:
        values[layout.slots * b3:, 1:4] = view.reshape(-1, 3)
    return layout, mi.TensorXf(values), cols, bbox, view_shape


def _view_shape(path, props, view):
    """The view lattice's vertices (X, Y, Z) from its coefficients ``view`` (Z, Y, X, 3) or the packed
    form's ``view_vertices``; None without one. A lattice of another shape, under 2 vertices an axis or
    with values not finite is refused naming ``path``."""
    if view is None and "view_vertices" not in props:
        return None
    if view is not None:
        if view.ndim != 4 or view.shape[3] != 3:
            raise ValueError(f"{path}: the view lattice must have shape (Z, Y, X, 3), got {view.shape}")
        if not np.all(np.isfinite(view)):
            raise ValueError(f"{path}: the view lattice contains NaN or Inf values")
        shape = tuple(int(v) for v in view.shape[2::-1])
    else:
        shape = tuple(int(v) for v in np.ravel(np.array(props.get("view_vertices"))))
    if len(shape) != 3 or min(shape) < 2:
        raise ValueError(f"{path}: the view lattice needs at least 2 vertices per axis, got {shape}")
    return shape
