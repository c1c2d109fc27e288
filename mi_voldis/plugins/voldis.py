"""The ``voldis`` integrator plugin: aligned-sample mixing of a full and a background radiance field."""
from __future__ import annotations

import contextlib

import drjit as dr
import mitsuba as mi
import numpy as np

from ..render import layers as layer_io
from ..render import march, mixing, quadrature
from ..render.occupancy import Occupancy, local_to_scene_np
from ..space import SceneSpace
from ..transforms import is_identity, to_matrix, to_scalar_transform

__variant__ = mi.variant()

ROLES = ("full", "bg", "fg_color", "residual")
MODES = mixing.LAYERS


class VolDisIntegrator(mi.ad.integrators.common.RBIntegrator):
    r"""
    .. _integrator-voldis:

    Volumetric disentanglement (:monosp:`voldis`)
    ---------------------------------------------

    .. pluginparameters::

     * - full, bg
       - |medium|
       - ``radiance_field`` media, nested by name: the full scene and the background (scene without
         the object). (Required)
     * - fg_color
       - |medium|
       - Optional foreground colour field (camouflage): replaces c_fg inside its box; its density is
         unused, so the foreground weights, and the depth, stay those of full - bg.
     * - residual
       - |medium|
       - Optional residual field (non-negative inpainting), rendered with its own weights and added
         to the main image: it can only add light.
     * - composition
       - |string|
       - Recombination rule: ``paper`` (Eq. 5), the ablations ``c2``, ``c3``, ``c4``, or ``density``
         (physically based density mixing). See :mod:`mi_voldis.render.mixing`. (Default: paper)
     * - mode
       - |string|
       - Layer returned as the main image: ``composite``, ``full``, ``bg`` (removal) or ``fg``.
         (Default: composite)
     * - samples
       - |int|
       - Samples per ray, shared by all fields (with ``step_size``: the most per ray). (Default: 128)
     * - step_size
       - |float|
       - If positive, each ray takes samples every ``step_size`` units of scene space over its
         interval (rounded to a whole number of equal steps), so short rays take fewer. (Default: 0)
     * - near
       - |float|
       - Rays start this far (world units) from their origin: forward-facing captures have nothing
         closer to the cameras than their near depth bound, and a fit must not put anything there.
         (Default: 0)
     * - fg_to_world, bg_to_world
       - |transform|
       - Moves the foreground (background): its fields are evaluated at T^-1 p. (Default: identity)
     * - occupancy_resolution, occupancy_threshold
       - |int|, |float|
       - Skip samples in cells of an occupancy grid (this many cells along the longest side of the
         fields' bounding box) where no field's density exceeds the threshold (per unit length of
         scene space). 0 disables skipping. (Default: 0, 0.01)
     * - strides
       - |boolean|
       - Contracted space with an occupancy grid: occupied cells where every field's optical depth per
         voxel stays below a level of :data:`mi_voldis.render.march.STRIDES` are crossed in that level's
         longer steps, never reaching density above it. (Default: false)
     * - stop_transmittance
       - |float|
       - A ray stops once every field's transmittance along it has fallen below this (early
         termination); its last sample takes the light left, so an opaque pixel's alpha is 1 and
         what lies behind changes the pixel by at most that much, times its difference from the
         last sample's colour. (Default: 1e-4)
     * - ndc_to_world, ndc_near, ndc_scale_x, ndc_scale_y
       - |transform|, |float|
       - Forward-facing scenes: sample and store the fields in the NDC space of this reference camera
         (Mitsuba frame), near plane and scales 2f/W, 2f/H; the fields' ``to_world`` then maps the unit
         cube into NDC space. See :mod:`mi_voldis.space`. (Default: world space)
     * - contract_to_world, contract_shell
       - |transform|, |float|
       - Scenes of any extent (360-degree captures with far background, forward-facing captures seen
         from other paths): sample and store the fields in contracted space, the normalising transform
         and the outer shell's width b (:mod:`mi_voldis.space`); needs ``step_size`` > 0, and then
         ``samples`` bounds the samples evaluated per ray. (Default: world space)

    Every ray is sampled at one set of points with one jitter u per ray (see
    :class:`mi_voldis.render.march.Path`); the fields are evaluated at those points (foreground lookups at
    T_fg^-1 p) and combined per sample, w_fg = w_full - w_bg and c_fg = c_full - c_bg (paper Eq. 3),
    then summed by the chosen rule. Quadrature: see :mod:`mi_voldis.render.quadrature`.

    Besides the main image (premultiplied RGB) it writes the AOVs ``A`` and ``depth.Z`` of the main
    layer and ``<layer>.R/G/B/A/Z`` for ``full``, ``bg``, ``fg`` (and ``res`` with a residual field):
    premultiplied colour, alpha = sum of the layer's weights, and expected ray distance.

    Differentiable in reverse mode (``mi.render`` + ``dr.backward``): the adjoint replays the march
    (path replay, from the lookup values the primal recorded while they fit
    :data:`mi_voldis.render.march.RECORD_BYTES`, else reading the grids again) and accumulates into
    every field's ``density`` and ``color``.

    .. tabs::

        .. code-tab:: xml

            <integrator type="voldis">
                <string name="composition" value="c4"/>
                <transform name="fg_to_world"> <translate value="0.2, 0, 0"/> </transform>
                <medium type="radiance_field" name="full"> ... </medium>
                <medium type="radiance_field" name="bg"> ... </medium>
            </integrator>
    """

    def __init__(self, props):
        super().__init__(props)
        self.composition = props.get("composition", "paper")
        if self.composition not in mixing.RULES:
            raise ValueError(f"voldis: composition must be one of {', '.join(mixing.RULES)}, "
                             f"got '{self.composition}'")
        self.mode = props.get("mode", "composite")
        if self.mode not in MODES:
            raise ValueError(f"voldis: mode must be one of {', '.join(MODES)}, got '{self.mode}'")
        self.samples = int(props.get("samples", 128))
        if self.samples < 1:
            raise ValueError(f"voldis: samples must be >= 1, got {self.samples}")
        self.step_size = float(props.get("step_size", 0.0))
        if self.step_size < 0:
            raise ValueError(f"voldis: step_size must be >= 0, got {self.step_size}")
        self.near = float(props.get("near", 0.0))
        if not self.near >= 0:
            raise ValueError(f"voldis: near must be >= 0, got {self.near}")
        self.fg_to_world = to_matrix(props.get("fg_to_world") if "fg_to_world" in props else None)
        self.bg_to_world = to_matrix(props.get("bg_to_world") if "bg_to_world" in props else None)
        for name, m in (("fg_to_world", self.fg_to_world), ("bg_to_world", self.bg_to_world)):
            if abs(np.linalg.det(m[:3, :3])) < 1e-12:
                raise ValueError(f"voldis: {name} must be invertible")
        if "contract_to_world" in props:
            self.space = SceneSpace("contract", to_matrix(props.get("contract_to_world")),
                                    shell=float(props.get("contract_shell", 1.0)))
            if self.step_size <= 0:
                raise ValueError("voldis: a contracted space needs step_size > 0 (scene units between samples)")
        elif "ndc_to_world" in props:
            self.space = SceneSpace("ndc", to_matrix(props.get("ndc_to_world")), props.get("ndc_near", 1.0),
                                    (props.get("ndc_scale_x", 1.0), props.get("ndc_scale_y", 1.0)))
        else:
            self.space = SceneSpace()
        self.stop_transmittance = float(props.get("stop_transmittance", quadrature.STOP_TRANSMITTANCE))
        if not 0 < self.stop_transmittance < 1:
            raise ValueError(f"voldis: stop_transmittance must be in (0, 1), got {self.stop_transmittance}")
        self.strides = bool(props.get("strides", False))
        if self.strides and not self.space.is_curved:
            raise ValueError("voldis: strides need a contracted space (contract_to_world)")
        self.fields = {}
        for name in props.keys():
            value = props.get(name)
            if isinstance(value, mi.Medium):
                if name not in ROLES:
                    raise ValueError(f"voldis: unknown field role '{name}' (expected {', '.join(ROLES)})")
                if not hasattr(value, "eval_local"):
                    raise ValueError(f"voldis: field '{name}' must be a radiance_field medium")
                self.fields[name] = value
        for role in ("full", "bg"):
            if role not in self.fields:
                raise ValueError(f"voldis: a '{role}' radiance_field medium is required")
        self._plans = {}
        self.occupancy = None
        self._strides = ()
        self.occupancy_threshold = float(props.get("occupancy_threshold", 0.01))
        self.occupancy_resolution = int(props.get("occupancy_resolution", 0))
        if self.occupancy_resolution < 0:
            raise ValueError(f"voldis: occupancy_resolution must be >= 0, got {self.occupancy_resolution}")
        if self.occupancy_resolution:
            self.update_occupancy(self.occupancy_resolution)

    def properties(self):
        """This integrator's properties (all but the fields), as :func:`mi_voldis.scene.build_integrator`
        and :func:`mi_voldis.scene.write_scene` take them: change some to build a variant of it."""
        props = {"composition": self.composition, "mode": self.mode, "samples": self.samples,
                 "step_size": self.step_size, "near": self.near, "occupancy_resolution": self.occupancy_resolution,
                 "occupancy_threshold": self.occupancy_threshold, "stop_transmittance": self.stop_transmittance,
                 "strides": self.strides,
                 **self.space.integrator_properties()}
        for name, m in (("fg_to_world", self.fg_to_world), ("bg_to_world", self.bg_to_world)):
            if not is_identity(m):
                props[name] = to_scalar_transform(m)
        return props

    def update_occupancy(self, resolution, threshold=None, extra=None):
        """Rebuild the occupancy grid from the fields' current densities (``resolution`` 0: off).
        ``extra``: scene-space points to mark occupied regardless (see :class:`Occupancy`)."""
        self.occupancy, self._strides = None, ()
        self._plans.clear()
        if resolution:
            lookups, sources = self._lookups()
            dense = [lk for lk in lookups if lk.key != sources.fg_color]
            lo, hi = self.scene_bounds()
            self.occupancy = Occupancy.build(dense, self.space, resolution,
                                             threshold or self.occupancy_threshold, lo, hi, extra)
            if self.strides:
                self._strides = self._stride_levels(dense, lo, hi, extra)
            self._plans.clear()
        return self.occupancy

    def _stride_levels(self, lookups, lo, hi, extra):
        """(occupancy, step) of each level of :data:`march.STRIDES` with a step longer than the march's: cells
        ``cells`` voxels (the fields' largest) across, marked where density reaches the level's optical depth
        per voxel; the step ``step`` voxels, at most 0.9 (cell - voxel)."""
        voxel, levels = self.occupancy.reach, []
        for depth, cells, step in march.STRIDES:
            resolution = max(1, int(np.ceil(float(np.max(hi - lo)) / (cells * voxel))))
            grid = Occupancy.build(lookups, self.space, resolution, depth / voxel, lo, hi, extra)
            level_step = min(step * voxel, 0.9 * (grid.cell_size - grid.reach))
            if level_step > self.step_size:
                levels.append((grid, level_step))
        return tuple(levels)

    def use_occupancy(self, occupancy, strides=()):
        """Skip with a given :class:`Occupancy` grid and, with ``strides``, step through thin cells with given
        levels (:attr:`stride_levels`; e.g. both restored from a checkpoint); None: off."""
        if strides and not self.strides:
            raise ValueError("voldis: stride levels given to an integrator without strides")
        self.occupancy, self._strides = occupancy, tuple(strides) if occupancy is not None else ()
        self._plans.clear()

    @property
    def stride_levels(self):
        """((occupancy, step), ...) of the strides in use (:meth:`_stride_levels`): what a checkpoint keeps,
        as the fields they were built from have changed since."""
        return self._strides

    def scene_bounds(self):
        """Scene-space axis-aligned bounds of every density-carrying box (after transforms)."""
        lookups, sources = self._lookups()
        corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], np.float64)
        pts = [local_to_scene_np(lk, self.space, corners) for lk in lookups if lk.key != sources.fg_color]
        pts = np.concatenate(pts)
        return pts.min(axis=0), pts.max(axis=0)

    # ---------------------------------------------------------------- Mitsuba object protocol
    def traverse(self, callback):
        for role, field in self.fields.items():
            callback.put(role, field, mi.ParamFlags.Differentiable)

    def to_string(self):
        return (f"VolDisIntegrator[composition={self.composition}, mode={self.mode}, "
                f"samples={self.samples}, step_size={self.step_size}, fields={list(self.fields)}]")

    def aov_names(self):
        """A, depth.Z, each layer's R, G, B, A, Z, then ``fg.coverage`` = sum_i max(w_fg,i, 0), the
        object's matte (:mod:`mi_voldis.compositing`; not differentiated)."""
        names = ["A", "depth.Z"]
        for layer in self.exr_layers:
            names += [f"{layer}.{c}" for c in "RGBAZ"]
        return names + ["fg.coverage"]

    @property
    def exr_layers(self):
        return layer_io.EXR_LAYERS + (("res",) if "residual" in self.fields else ())

    # ---------------------------------------------------------------------------- planning
    def plan(self, layers=None, samples=None, distortion=(), near_grad=0.0):
        """The :class:`march.Plan` computing ``layers`` (default: all) with ``samples`` per ray, the
        distortion loss of the ``distortion`` layers, and with ``near_grad`` > 0 gradients scaled near
        the cameras (:mod:`mi_voldis.render.march`)."""
        layers = tuple(layers or (MODES + (("res",) if "residual" in self.fields else ())))
        key = (layers, samples or self.samples, tuple(distortion), float(near_grad), self.stop_transmittance)
        if key not in self._plans:
            lookups, sources = self._lookups()
            needed = mixing.needed_sources(self.composition, sources, layers)
            boxes = tuple(lk.to_local for lk in lookups
                          if lk.key != sources.fg_color and lk.warp is None)  # density-carrying boxes
            skip = self.skip_length()
            self._plans[key] = march.Plan(tuple(lk for lk in lookups if lk.key in needed), sources,
                                          self.composition, layers, key[1], boxes, self.space, self.occupancy,
                                          self.step_size, skip, key[2], self.near, key[3],
                                          quadrature.stop_depth(self.stop_transmittance), self._strides)
        return self._plans[key]

    @contextlib.contextmanager
    def stopped_at(self, transmittance):
        """Inside the ``with`` block rays stop at ``transmittance`` instead of ``stop_transmittance``: the
        render of the same fields and skipping by a scene with that stop (a fit's log scores what its
        fitted scene will render while its steps keep their own stop)."""
        if not 0 < transmittance < 1:
            raise ValueError(f"voldis: stop_transmittance must be in (0, 1), got {transmittance}")
        own, self.stop_transmittance = self.stop_transmittance, float(transmittance)
        try:
            yield self
        finally:
            self.stop_transmittance = own

    def skip_length(self):
        """Contracted space: the step across an empty occupancy cell. Density reaches at most one voxel
        into the one-cell dilation around occupied cells (:class:`Occupancy`), so a step shorter than a
        cell minus the largest voxel, taken from an empty cell, never reaches density."""
        if self.occupancy is None:
            return 0.0
        return max(0.9 * (self.occupancy.cell_size - self.occupancy.reach), self.step_size)

    def _lookups(self):
        ident = np.eye(4)
        inv_fg, inv_bg = np.linalg.inv(self.fg_to_world), np.linalg.inv(self.bg_to_world)

        def lookup(key, role, inv_t):
            field = self.fields[role]
            if self.space.is_world:
                return march.Lookup(key, field, field.world_to_local @ inv_t, inv_t)
            warp = None if is_identity(inv_t) else inv_t  # NDC: transform in world space between warps
            return march.Lookup(key, field, field.world_to_local, inv_t, warp)

        full = lookup("full@p", "full", ident)
        bg = lookup("bg@p" if is_identity(self.bg_to_world) else "bg@b", "bg", inv_bg)
        full_q = full if is_identity(self.fg_to_world) else lookup("full@q", "full", inv_fg)
        bg_q = bg if np.array_equal(self.fg_to_world, self.bg_to_world) else lookup("bg@q", "bg", inv_fg)
        lookups = {lk.key: lk for lk in (full, bg, full_q, bg_q)}
        extra = {}
        if "fg_color" in self.fields:
            lookups["fg_color@q"] = lookup("fg_color@q", "fg_color", inv_fg)
            extra["fg_color"] = "fg_color@q"
        if "residual" in self.fields:
            lookups["residual@p"] = lookup("residual@p", "residual", ident)
            extra["residual"] = "residual@p"
        sources = mixing.Sources(full.key, bg.key, full_q.key, bg_q.key, **extra)
        return list(lookups.values()), sources

    # ----------------------------------------------------------------------------- sampling
    def sample(self, mode, scene, sampler, ray, δL, δaovs, state_in, active, keep_record=False, **kwargs):
        """Primal: the main image, validity, AOVs and the :class:`march.Forward` state (``keep_record``:
        with the lookups' values for the adjoint). Backward: the adjoint of that state."""
        if mode == dr.ADMode.Forward:
            self.render_forward(scene, None)
        if mode == dr.ADMode.Primal:
            plan = self.plan()
            u = sampler.next_1d(active)
            rays = march.prepare_rays(plan, mi.Point3f(dr.detach(ray.o)), mi.Vector3f(dr.detach(ray.d)), 0.0,
                                      ray.maxt)
            fwd = march.forward(plan, rays, u, active, keep_record)
            out = layer_io.finalize(layer_io.raw_sums(plan, fwd.acc))
            main = out[self.mode]
            L = main[0] + out["res"][0] if "res" in out else main[0]
            aovs = [main[1], main[2]]
            for layer in self.exr_layers:
                rgb, a, z = out[layer]
                aovs += [rgb[0], rgb[1], rgb[2], a, z]
            aovs.append(fwd.stats["fg_coverage"])
            return L, rays.hit, aovs, fwd
        fwd = state_in
        raw = layer_io.finalize_adjoint(layer_io.raw_sums(fwd.plan, fwd.acc), self._layer_grads(δL, δaovs))
        accumulate_gradients(fwd.plan, march.backward(fwd, raw))
        return δL, fwd.rays.hit, [], None

    def render_forward(self, scene, params, sensor=0, seed=0, spp=0):
        raise NotImplementedError("voldis: forward-mode differentiation is not supported; use reverse "
                                  "mode (mi.render + dr.backward)")

    def render_backward(self, scene, params, grad_in, sensor=0, seed=0, spp=0):
        """Reverse-mode derivative of ``render``: image adjoint -> field gradients.

        Replaces ``RBIntegrator.render_backward``, which in Mitsuba 3.9.1 multiplies AOVs by the
        Spectrum ray weight and so cannot back-propagate through an integrator that has AOVs."""
        if isinstance(sensor, int):
            sensor = scene.sensors()[sensor]
        film = sensor.film()
        with dr.suspend_grad():
            sampler, spp = self.prepare(sensor, seed, spp, self.aov_names())
            ray, weight, pos = self.sample_rays(scene, sensor, sampler)
            δL, δaovs = film_adjoint(film, pos, weight, len(self.aov_names()), grad_in)
            args = dict(scene=scene, ray=ray, depth=mi.UInt32(0), active=mi.Bool(True))
            *_, state = self.sample(dr.ADMode.Primal, sampler=sampler.clone(), δL=None, δaovs=None,
                                    state_in=None, keep_record=True, **args)
            self.sample(dr.ADMode.Backward, sampler=sampler, δL=δL, δaovs=δaovs, state_in=state, **args)
            dr.eval()

    def _layer_grads(self, δL, δaovs):
        """Adjoints of each layer's (RGB, A, Z) from those of the main image and the AOVs."""
        zero = mi.Float(0.0)
        grads = {layer: [mi.Color3f(0.0), zero, zero] for layer in MODES + ("res",)}
        main = grads[self.mode]
        grads[self.mode] = [main[0] + δL, main[1] + δaovs[0], main[2] + δaovs[1]]
        grads["res"] = [mi.Color3f(δL), zero, zero]
        for n, layer in enumerate(self.exr_layers):
            k = 2 + 5 * n
            g = grads[layer]
            grads[layer] = [g[0] + mi.Color3f(δaovs[k], δaovs[k + 1], δaovs[k + 2]),
                            g[1] + δaovs[k + 3], g[2] + δaovs[k + 4]]
        return {layer: tuple(g) for layer, g in grads.items() if layer in self.plan().layers}


def film_adjoint(film, pos, weight, n_aovs, grad_in):
    """Adjoint of splatting samples into ``film`` and developing it: per-sample (dL, [d_aov]).

    Splatting is linear in the sample values, so differentiating a splat of ones gives it exactly."""
    n = dr.width(pos)
    with dr.resume_grad():
        value = dr.ones(mi.Color3f, n)
        aovs = [dr.ones(mi.Float, n) for _ in range(n_aovs)]
        dr.enable_grad(value, aovs)
        rgb = value * weight
        channels = [rgb[0], rgb[1], rgb[2]]
        if mi.has_flag(film.flags(), mi.FilmFlags.Alpha):
            channels.append(dr.ones(mi.Float, n))
        channels += [dr.ones(mi.Float, n)] + aovs  # sample weight, then AOVs
        block = film.create_block()
        block.put(pos, channels)
        film.put_block(block)
        image = film.develop()
        dr.set_grad(image, grad_in)
        dr.enqueue(dr.ADMode.Backward, image)
        dr.traverse(dr.ADMode.Backward)
        grads = dr.grad(value), [dr.grad(a) for a in aovs]
    film.clear()
    return grads


def accumulate_gradients(plan, grads):
    """Hand the packed-grid gradients of :func:`march.backward` on to the fields' parameters (one AD
    traversal through the packing to ``density`` and ``color``)."""
    with dr.resume_grad():
        for f in plan.fields:
            if grads[id(f)] is not None:
                dr.accum_grad(f.packed, grads[id(f)])
                dr.enqueue(dr.ADMode.Backward, f.packed)
        dr.traverse(dr.ADMode.Backward)


mi.register_integrator("voldis", lambda props: VolDisIntegrator(props))
