"""The ``radiance_field`` medium plugin: a voxel-grid radiance field over a box."""
from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from .. import grid
from ..activations import sigmoid, softplus
from ..io.vol import grid_values, read_header, read_vol
from ..transforms import to_matrix

__variant__ = mi.variant()

SH_DEGREES = {3: 0, 12: 1, 27: 2}  # colour channels -> spherical-harmonic degree
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
       - Raw colour at the same vertices: 3 channels (RGB), or 12 / 27 channels for spherical
         harmonics of degree 1 / 2, ordered basis-major (channel 3 k + rgb). (Required)
       - |exposed|, |differentiable|

     * - to_world
       - |transform|
       - Maps the unit cube [0, 1]^3 onto the field's box. (Default: the bounding box stored in the
         density ``.vol`` header; the unit cube for tensors)

     * - density_scale
       - |float|
       - s in sigma = s softplus(D): fitting sets it to one over a voxel's size so that raw values
         are densities per voxel, as DVGO does (a surface is then opaque at raw ~ 10, a value Adam
         reaches in tens of steps, instead of ~ 10 / voxel). (Default: 1)

    The field answers only one question, density and colour at points:

    .. math::

        \sigma(p) = s \, \mathrm{softplus}(D(p)), \qquad
        c(p, d) = \mathrm{sigmoid}\Big(C_0(p) + \sum_{k \ge 1} \frac{Y_k(d)}{Y_0} C_k(p)\Big)

    where D and C_k are trilinear interpolants of the raw grids (activation after interpolation, as
    DVGO does, which gives sharp surfaces from coarse grids), Y_k are real spherical harmonics and d is
    the direction of travel. softplus keeps a gradient everywhere (no dead cells at initialisation);
    densities are per unit of world length. Outside the box the density is 0. Dividing by Y_0 makes
    C_0 the logit of the mean colour at every degree, so raising a field's degree by appending zero
    coefficients does not change it.

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
        density, bbox = _load_grid(props, "density", name)
        color, _ = _load_grid(props, "color", name)
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
        self._density, self._color, self._packed = density, color, None
        self.parameters_changed()

    # ---------------------------------------------------------------- Mitsuba object protocol
    def traverse(self, callback):
        callback.put("density", self.density, mi.ParamFlags.Differentiable)
        callback.put("color", self.color, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys=None):
        d, c = self.density, self.color
        if len(d.shape) != 4 or d.shape[3] != 1:
            raise ValueError(f"radiance_field: density must have shape (Z, Y, X, 1), got {tuple(d.shape)}")
        if len(c.shape) != 4 or tuple(c.shape[:3]) != tuple(d.shape[:3]):
            raise ValueError(f"radiance_field: color must have shape {tuple(d.shape[:3])} + (C,), "
                             f"got {tuple(c.shape)}")
        if c.shape[3] not in SH_DEGREES:
            raise ValueError(f"radiance_field: color needs 3, 12 or 27 channels (RGB or SH degree 1/2), "
                             f"got {c.shape[3]}")
        if min(d.shape[:3]) < 2:
            raise ValueError(f"radiance_field: the grid needs at least 2 vertices per axis, got "
                             f"{grid.grid_shape(d)}")
        self.shape = grid.grid_shape(d)
        self.sh_degree = SH_DEGREES[c.shape[3]]
        self.channels = 1 + c.shape[3]
        self.width = grid.packet_width(self.channels)
        self._packed = None  # packed on first use: a step that sets both tensors packs them once

    # ------------------------------------------------------------ values: tensors or packed
    density = _unpacked_tensor("_density", "Raw density tensor (Z, Y, X, 1).")
    color = _unpacked_tensor("_color", "Raw colour tensor (Z, Y, X, C).")

    @property
    def packed(self):
        """Density and colour interleaved per vertex (:func:`mi_voldis.grid.pack`): what lookups read."""
        if self._packed is None:
            with dr.resume_grad():  # first read may happen where gradients are suspended (mi.render's primal)
                self._packed = grid.pack([self._density, self._color])
            dr.eval(self._packed)
        return self._packed

    def set_packed(self, packed):
        """Make ``packed`` (the layout of :attr:`packed`, same grid and channels) the field's values.

        Fitting optimises this array directly, so that a step neither packs the two tensors nor
        unpacks their gradients; ``density`` and ``color`` are unpacked from it when next read."""
        expected = self.shape[0] * self.shape[1] * self.shape[2] * self.width
        if dr.width(packed) != expected:
            raise ValueError(f"radiance_field: packed grid needs {expected} values, got {dr.width(packed)}")
        self._packed, self._density, self._color = packed, None, None

    def _unpack(self):
        if self._density is None:
            self._density, self._color = grid.unpack(self._packed, [1, self.channels - 1],
                                                     self.shape[::-1])

    def to_string(self):
        return (f"RadianceField[shape={self.shape}, sh_degree={self.sh_degree}, "
                f"density_scale={self.density_scale}, to_world={self.to_world.tolist()}]")

    # -------------------------------------------------------------------- field evaluation
    def eval_local(self, p, d, data=None, active=True):
        """Density and colour at local points ``p`` (unit-cube coordinates), seen along ``d``.

        ``data`` is the packed grid to read (default: this field's own ``packed`` array; the
        integrator passes gradient-tracked copies during its adjoint pass). Returns
        ``(sigma, color)``; sigma is 0 outside the unit cube."""
        inside = dr.all((p >= 0.0) & (p <= 1.0)) & active
        return self.activate(self.lookup(p, data, inside), d, inside)

    def lookup(self, p, data=None, active=True):
        """Raw values at local points ``p`` (clamped to the unit cube): the ``channels`` interpolated
        grid channels, density first (Float arrays)."""
        return grid.trilinear(self.packed if data is None else data, self.shape, self.width,
                              self.channels, p, active)

    def activate(self, v, d, active=True):
        """``(sigma, color)`` from raw values ``v`` (:meth:`lookup`) seen along ``d``: sigma =
        s softplus(v_0) where ``active`` (0 elsewhere), colour = sigmoid of the SH sum."""
        sigma = dr.select(active, self.density_scale * softplus(v[0]), 0.0)
        logits = [v[1], v[2], v[3]]
        if self.sh_degree > 0:
            basis = dr.sh_eval(dr.normalize(d), self.sh_degree)
            for k in range(1, len(basis)):
                scale = basis[k] * (1.0 / SH_Y0)
                for ch in range(3):
                    logits[ch] = dr.fma(scale, v[1 + 3 * k + ch], logits[ch])
        return sigma, mi.Color3f(sigmoid(logits[0]), sigmoid(logits[1]), sigmoid(logits[2]))

    def sample_interaction(self, ray, sample, channel, active):
        raise RuntimeError("radiance_field is evaluated by the 'voldis' integrator only; "
                           "it does not scatter light for Mitsuba's path tracers")


def _load_grid(props, key, name):
    """Tensor of property ``key`` (file name, tensor or VolumeGrid) and the file's bbox (or None)."""
    if key not in props:
        raise ValueError(f"{name}: radiance_field needs a '{key}' property (.vol file or tensor)")
    value = props.get(key)
    bbox = None
    if isinstance(value, str):
        path = str(mi.file_resolver().resolve(value))
        header = read_header(path)
        bbox = (header[4], header[5])
        value = read_vol(path)
    elif isinstance(value, mi.VolumeGrid):
        value = grid_values(value)
    elif not isinstance(value, mi.TensorXf):
        raise ValueError(f"{name}: '{key}' must be a .vol file name, mi.TensorXf or mi.VolumeGrid, "
                         f"got {type(value).__name__}")
    tensor = mi.TensorXf(value)
    if not dr.all(dr.isfinite(tensor.array)):
        raise ValueError(f"{name}: '{key}' contains NaN or Inf values")
    return tensor, bbox


mi.register_medium("radiance_field", lambda props: RadianceField(props))
