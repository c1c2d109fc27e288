"""One fitting phase as a problem for :func:`mi_voldis.optim.loop.optimize`: which fields, which
layers, which rays, the paper's losses on them and the regularisers."""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

from .. import exposure
from ..data.scene_box import rig_extent
from ..device import from_numpy
from ..field.bricks import EMPTY_DENSITY
from ..field.state import MEAN_CHANNELS, neighbour_vertices
from ..losses import background_loss, depth_smoothness_loss, distortion_loss, full_loss
from ..optim.average import moving_average, stride, window_decay
from ..optim.parameters import PackedParameters
from ..raybank import tile_pairs
from ..regularizers import add_tv_gradient, sparsity_gradient, tv_gradient
from ..render.rays import render_rays
from .fields import fit_integrator, memory_bound, occupancy_resolution, occupancy_sigma, refine
from .free_space import training_free_space
from .observed import view_rate_scale
from .schedule import REPLAN_EVERY, capped, plan_cost, rescale_after_cap, resolution_at


def backdrop(ds, rng, n):
    """Colour seen through a layer's remaining transmittance in training: the dataset's background
    colour for composited RGBA images, else a random colour per ray, so that no fit can explain a
    pixel with a half-transparent surface over black (every ray of a closed capture ends on one)."""
    bg = ds.meta.get("background_color")
    if bg is not None:
        return mi.Color3f(*bg)
    return from_numpy(mi.Color3f, rng.random((3, n), np.float32).T)


def psnr_of(mse):
    return -10 * np.log10(max(float(mse[0]), 1e-12))


def view_lattice_zero(field):
    """Whether ``field`` has a view lattice and every one of its coefficients is 0."""
    if getattr(field, "view_shape", None) is None:
        return False
    start = (field.rows - int(np.prod(field.view_shape))) * field.width
    view = dr.gather(mi.Float, field.packed, dr.arange(mi.UInt32, dr.width(field.packed) - start) + start)
    return bool(dr.all(view == 0.0))


class FieldFit:
    """One fitting phase: the fields of ``roles`` fitted through ``layers`` to rays of ``bank``
    (``pool``: flat pixel indices to draw from), their updates masked to ``hull`` (a Float per stored
    vertex) when given, the density's to ``density_hull`` if given too; ``schedule``: follow the
    resolution schedule and start empty-space skipping; ``view_rates``: the learning rates per brick by
    the training views that observe it (``lr_views``, :mod:`mi_voldis.fit.observed`);
    ``view_dependence_late``: view-dependent colour fitted from ``sh_view_from`` of the planned steps on
    (:meth:`view_onset`); ``average``: the fields' iterates averaged over the last stage (:meth:`average`)."""

    def __init__(self, inputs, state, roles, layers, bank, pool=None, hull=None, phase=0, schedule=True, adam=None,
                 rates=None, tv=None, fit_exposure=False, prior=None, density_hull=None, view_rates=False,
                 view_dependence_late=False, average=False):
        self.inputs, self.state, self.roles, self.layers, self.bank = inputs, state, roles, layers, bank
        self.pool, self.hull, self.phase, self.schedule = pool, hull, phase, schedule
        self.density_hull = density_hull
        self.view_rates = view_rates and inputs.cfg.lr_views > 0
        self.view_dependence_late = view_dependence_late
        self.averaged = average and inputs.cfg.average_window > 0
        # near-camera gradient scaling, r in world units (mi_voldis.render.march), in the full field's fit:
        # the background refit steps the object's region, away from the cameras, where it would only reweigh
        # the colour prior's views
        self.near_grad = 0.0
        if inputs.cfg.near_grad and "full" in roles:
            self.near_grad = inputs.cfg.near_grad * rig_extent([inputs.ds.cameras[v] for v in inputs.ds.train])
        self.prior = prior  # (RayBank, pool): the guided background's 2D colour prior (mi_voldis.fit.guide)
        self.fit_exposure = fit_exposure and state.exposure is not None
        self.adam = state.adam if adam is None else adam
        cfg = inputs.cfg
        self.rates = (cfg.lr_density, cfg.lr_color) if rates is None else rates  # (density, colour)
        self.tv = (cfg.tv_density, cfg.tv_color) if tv is None else tv  # TV weights (density, colour)
        self.on_stage = None  # called with the step at each later stage's start (before the fields are refined)
        # and every REPLAN_EVERY steps: the schedule may be rescaled there
        self.rebuild(resume=True)

    # -- plumbing
    def rebuild(self, resume=False):
        """The integrator and parameters over the state's fields. Skipping uses a fresh occupancy grid,
        or with ``resume`` the one this phase built last (a phase resumed from a checkpoint then skips
        exactly what it skipped before the checkpoint)."""
        self.integrator = fit_integrator(self.inputs, self.state)
        if not resume:  # the lattice or the colour's channels may have changed: an average starts afresh
            self.state.averages = {}
        self.params = PackedParameters({r: self.integrator.fields[r] for r in self.roles})
        cameras = [self.inputs.ds.cameras[v] for v in self.inputs.ds.train]
        for r in self.roles:
            self.adam.lrs[f"{r}.packed"] = self.params.per_slot(r, *self.rates)
            self.adam.scales.pop(f"{r}.packed", None)
            self.adam.growth.pop(f"{r}.packed", None)
            self.adam.subsets.pop(f"{r}.packed", None)
            if self.hull is not None:  # Adam keeps moments for the region's vertices alone
                self.adam.subsets[f"{r}.packed"] = self.refit_elements(self.integrator.fields[r])
            if self.view_rates and not self.final_stage(r):  # the lattice may have changed: views counted anew
                cfg, f = self.inputs.cfg, self.state.fields[r]
                scale = view_rate_scale(self.inputs.space, f, cameras, cfg.lr_views, cfg.lr_views_quantile)
                if cfg.lr_views_growth:  # the density channel's growth only
                    channel = dr.arange(mi.UInt32, dr.width(scale)) % f.width
                    self.adam.growth[f"{r}.packed"] = dr.select(channel == 0, scale, 1.0)
                else:
                    self.adam.scales[f"{r}.packed"] = scale
        if self.fit_exposure:
            self.params["exposure"] = self.state.exposure
            self.adam.lrs["exposure"] = self.inputs.cfg.exposure_lr
        self.keys = list(self.params)
        self.free = self.free_space(resume)
        self.keep_free()
        self.adam.holds.pop("full.packed", None)
        if self.free is not None:  # Adam writes it back after each step: its update may have grown it
            self.adam.holds["full.packed"] = (self.free, EMPTY_DENSITY)
        self.view_zero = {r: view_lattice_zero(self.integrator.fields[r]) for r in self.roles}
        self.neighbours = {}  # per role, made when the TV first needs them
        if resume and self.state.occupancy is not None and self.state.occupancy_phase == self.phase:
            self.integrator.use_occupancy(self.state.occupancy, self.state.strides)
        elif self.state.occupancy_on:
            self.update_occupancy()

    def free_space(self, resume=False):
        """Packed indices of the full field's density at the vertices the masks prove empty (``free_space``,
        :mod:`mi_voldis.fit.free_space`), None where none is kept empty (another phase, no masks, the
        setting off). Made anew on each lattice, once the field is fitted (a checkpoint taken) with its
        surfaces telling an occluder's gaps in a mask from notches; ``resume``: the state's, as the stage
        made them."""
        if "full" not in self.roles:
            return None
        field = self.state.fields["full"]
        if not (resume and self.state.free is not None):
            fitted = self.integrator if self.state.step > 0 else None
            free = training_free_space(self.inputs, field, fitted)
            self.state.free = None if free is None else np.flatnonzero(free).astype(np.uint32)
            if self.inputs.progress and free is not None:
                print(f"free space: {len(self.state.free)} of {int(field.vertices)} stored vertices kept empty (the "
                      "masks' cones before the visual hull)", file=sys.stderr)
        if self.state.free is None or not len(self.state.free):
            return None
        return from_numpy(mi.UInt32, self.state.free * np.uint32(field.width))

    def keep_free(self):
        """The free space's density set empty (at the start of a stage; Adam's ``holds`` keep it so)."""
        if self.free is None:
            return
        with dr.suspend_grad():
            packed = self.integrator.fields["full"].packed
            dr.scatter(packed, EMPTY_DENSITY, self.free)
            dr.eval(packed)

    def refit_elements(self, field):
        """The packed elements of ``field`` a refit masked to ``hull`` may change (UInt32, ascending): density
        and the mean colour of the vertices where ``hull`` is not 0, but the empty brick's (slot 0, which
        stands for every unallocated brick). Elsewhere the masked gradient is zero, so Adam would never move
        them; the view-dependent coefficients stay as the background's start left them (0 where it
        inpaints the hole: :func:`~mi_voldis.field.state.without_view_dependence`). Empty where the hull is."""
        inside = (self.hull != 0.0) & (dr.arange(mi.UInt32, dr.width(self.hull)) >= field.layout.vertices_per_brick)
        vertices = dr.compress(inside)
        if dr.width(vertices) == 0:
            return mi.UInt32()
        return dr.repeat(vertices, MEAN_CHANNELS) * field.width + dr.tile(dr.arange(mi.UInt32, MEAN_CHANNELS),
                                                                          dr.width(vertices))

    def view_onset(self):
        """The step from which view-dependent colour is fitted: ``sh_view_from`` of the full phase's planned
        steps in its fit (never before the plan), from the start in any other or without the setting."""
        view_from = self.inputs.cfg.sh_view_from if self.view_dependence_late else 0.0
        if not view_from:
            return 0
        return np.inf if self.state.steps_full is None else int(view_from * self.state.steps_full)

    def depth_smooth_end(self):
        """The step at which the depth smoothness stops: ``depth_smooth_until`` of the full phase's planned
        steps (every step where that setting is 1, or before the plan is made)."""
        until = self.inputs.cfg.depth_smooth_until
        if until >= 1.0 or self.state.steps_full is None:
            return np.inf
        return int(until * self.state.steps_full)

    def final_stage(self, role):
        """Whether the field of ``role`` is at the planned schedule's last resolution and ``lr_views_final``
        is off (the per-brick rates then stop)."""
        state = self.state
        return (not self.inputs.cfg.lr_views_final and state.steps_full is not None and
                max(state.fields[role].shape) >= state.schedule[-1][1])

    def update_occupancy(self):
        extra = self.state.hull_points if self.hull is not None else None
        self.state.occupancy = self.integrator.update_occupancy(occupancy_resolution(self.inputs.cfg, self.state),
                                                                occupancy_sigma(self.inputs.cfg, self.state), extra)
        self.state.strides = self.integrator.stride_levels
        self.state.occupancy_phase = self.phase

    def sync_states(self):
        """Copy the optimised values back into the fit state's fields (and colour corrections)."""
        for r in self.roles:
            self.state.fields[r].data = self.integrator.fields[r].packed
        if self.fit_exposure:
            self.state.exposure = self.params["exposure"]

    # -- schedule
    def before_step(self, step):
        cfg, state = self.inputs.cfg, self.state
        upsample = self.schedule and any(step == start for start, _ in state.schedule[1:])
        if self.on_stage is not None and (upsample or (self.schedule and step % REPLAN_EVERY == 0)):
            self.on_stage(step)
        if upsample:
            self.sync_states()
            planned = resolution_at(state.schedule, step)
            bound = memory_bound(self.inputs, state)  # None where the user set the grid: then no bound applies
            used, reason, weight = refine(self.inputs, state, self.integrator, self.roles, planned, bound,
                                          None if bound is None else cfg.max_samples)
            if weight is not None and weight != cfg.carve_weight:  # memory bound this stage: a tighter carve
                state.plan.setdefault("carve_tightened", []).append([step, weight])
            if used < planned:  # the carved lattice would outgrow max_memory_gib, or its rays max_samples: this
                # stage and later ones stop at it
                if "reference_msps" in state.plan:  # the default plan: the seconds saved buy steps at the cap
                    state.schedule, state.steps_full = rescale_after_cap(
                        state.schedule, state.steps_full, step, used, plan_cost(state.plan, state.schedule[0][1]),
                        state.plan["budget_seconds"])
                    state.plan.setdefault("rescaled", []).append([step, state.steps_full])
                else:  # a wall-clock budget: the next replan (schedule.rescale) fills it
                    state.schedule = capped(state.schedule, used, step)
                state.plan.setdefault(f"{reason}_caps", []).append([step, planned, used])
                if self.inputs.progress:
                    why = (f"its carved grid would pass max_memory_gib {cfg.max_memory_gib:g}" if reason == "memory"
                           else f"its rays would pass max_samples {cfg.max_samples}")
                    print(f"{reason}: the stage from step {step} stops at {used} (planned {planned}): {why}; "
                          f"{state.steps_full} steps in all", file=sys.stderr)
            self.adam.reset()
            self.rebuild()
        for r in self.roles:  # an all-0 view lattice (a new field's before the onset) adds nothing: not read
            self.integrator.fields[r].view_enabled = step >= self.view_onset() or not self.view_zero[r]
        start = self.schedule and cfg.occupancy_at_step and step >= cfg.occupancy_at_step and not state.occupancy_on
        if start or (state.occupancy_on and step % cfg.occupancy_every == 0 and step > 0 and not upsample):
            state.occupancy_on = True
            self.sync_states()
            self.update_occupancy()

    def after_step(self, step):
        if self.fit_exposure:  # shared corrections belong to the scene's colours (mi_voldis.exposure)
            self.params["exposure"] = exposure.centre(self.params["exposure"])
        # the state holds the values Adam just made, not the ones before them: a stale copy of every field
        # would stay alive until the next occupancy update (a grid's worth of memory at the step's peak)
        self.sync_states()
        if self.averaged:
            self.average(step)

    def average(self, step):
        """From the planned last stage's first step on, ``state.averages`` follows the fields' moving average
        (:mod:`mi_voldis.optim.average`) over a window of ``average_window`` of that stage's steps, every
        :func:`~mi_voldis.optim.average.stride` steps; the full phase's fields are that average at its end
        (:meth:`take_averages`)."""
        state = self.state
        if state.steps_full is None or step < state.schedule[-1][0]:
            return
        start = state.schedule[-1][0]
        window = self.inputs.cfg.average_window * (state.steps_full - start)
        every = stride(window)
        if (step - start) % every:
            return
        beta = window_decay(window, every)
        for r in self.roles:
            state.averages[r] = moving_average(None if step == start else state.averages.get(r),
                                               self.integrator.fields[r].packed, beta)

    def take_averages(self):
        """The fields become their averages (where :meth:`average` made some), which are then dropped."""
        for r, a in self.state.averages.items():
            self.state.fields[r].data = a
        self.state.averages = {}

    # -- loss
    def loss(self, step):
        cfg = self.inputs.cfg
        rng = np.random.default_rng([cfg.seed, self.phase, step])
        n = cfg.batch_rays
        o, d, color, mask, view = self.bank.batch(rng, n, self.pool, cfg.batch_tile)
        distortion = tuple(layer for layer in self.layers if layer in ("full", "bg")) if cfg.distortion else ()
        out = render_rays(self.integrator, o, d, from_numpy(mi.Float, rng.random(n, np.float32)), self.layers,
                          distortion=distortion, near_grad=self.near_grad)
        behind = backdrop(self.inputs.ds, rng, n)
        loss = mi.Float(0.0)
        # what the step's cost counts (mi_voldis.fit.schedule.counted_step_seconds): its samples, the floats it steps
        stats = {"samples": float(dr.sum(out["evaluated"])[0]),
                 "floats": float(sum(dr.width(self.integrator.fields[r].packed) for r in self.roles))}
        extent = float(np.max(self.state.hi - self.state.lo))  # ray positions in units of the scene box
        for layer in distortion:
            loss += (cfg.distortion / extent) * distortion_loss(out["distortion"][layer], mask, cfg.distortion_object)

        def photo(rgba, behind, view):  # what the photograph shows: the layer over the backdrop, colour-corrected
            pred = rgba[0] + (1.0 - rgba[1]) * behind
            if self.state.exposure is None:
                return pred
            params = self.params["exposure"] if self.fit_exposure else dr.detach(self.state.exposure)
            return exposure.apply(params, view, pred)
        if "full" in self.layers:
            err = full_loss(photo(out["full"], behind, view), color)
            loss += err
            stats["psnr"] = psnr_of(err)
        if "bg" in self.layers:
            err = background_loss(photo(out["bg"], behind, view), color, mask)
            loss += err
            stats["psnr_bg"] = psnr_of(err)
        if "full" in self.layers and cfg.depth_smooth > 0 and step < self.depth_smooth_end():
            # depth smoothness on tiles of training rays
            tile = cfg.depth_smooth_tile
            tiles = max(1, int(cfg.depth_smooth_rays * n) // (tile * tile))
            o, d, target, _, _ = self.bank.batch(rng, tiles * tile * tile, self.pool, tile)
            u = from_numpy(mi.Float, rng.random(tiles * tile * tile, np.float32))
            _, alpha, depth = render_rays(self.integrator, o, d, u, ("full",))["full"]
            depth = self.inputs.space.scene_depth(o, d, depth)  # contracted: far depths squeezed together
            pairs = tile_pairs(tiles, tile)
            pairs = mi.UInt32(pairs[:, 0]), mi.UInt32(pairs[:, 1])
            loss += cfg.depth_smooth * depth_smoothness_loss(depth, alpha, target, pairs, cfg.depth_smooth_edge)
        if self.prior is not None and cfg.prior_weight > 0:  # L_prior on masked rays (mi_voldis.fit.guide)
            bank, pool = self.prior
            m = max(1, int(cfg.prior_rays * n))
            o, d, target, _, prior_view = bank.batch(rng, m, pool, cfg.batch_tile)
            prior = render_rays(self.integrator, o, d, from_numpy(mi.Float, rng.random(m, np.float32)), ("bg",))
            err = full_loss(photo(prior["bg"], backdrop(self.inputs.ds, rng, m), prior_view), target)
            loss += cfg.prior_weight * err
            stats["psnr_prior"] = psnr_of(err)
        if self.fit_exposure:
            loss += exposure.penalty(self.params["exposure"], cfg.exposure_weight)
        return loss, stats

    def extra_gradients(self, step, grads):
        """Regularisers on the packed grids (channel 0 density, then colour; padding untouched):
        sparsity on activated density, total variation every ``tv_every`` steps, and the hull mask; the
        empty brick gets none, nor a view lattice. Before :meth:`view_onset` the view-dependent
        coefficients get no gradient (they stay as they are, 0 in a new field)."""
        cfg = self.inputs.cfg
        tv = cfg.tv_every if step % cfg.tv_every == 0 else 0.0
        for r in self.roles:
            key, f = f"{r}.packed", self.integrator.fields[r]
            if key not in grads:
                continue
            values = dr.detach(self.params[key])
            vertices = f.layout.slots * f.layout.vertices_per_brick  # the bricks'; a view lattice's follow them
            lattice = vertices * f.width
            subset = self.adam.subsets.get(key)  # inside the hull: the gradient at its elements alone
            if subset is not None and dr.width(subset) == 0:  # an empty hull: nothing to step
                continue
            index = dr.arange(mi.UInt32, dr.width(values)) if subset is None else subset
            channel = index % f.width
            weights = None
            if tv:  # tv_gradient averages over every slot: rescale to per-vertex means of each channel group
                if r not in self.neighbours:
                    self.neighbours[r] = neighbour_vertices(self.state.fields[r])
                    # building the table leaves blocks of sizes no step allocates in Dr.Jit's cache, held
                    # for the whole stage: give them back
                    dr.flush_malloc_cache()
                weights = self.params.per_slot(r, tv * self.tv[0] * f.width,
                                               tv * self.tv[1] * f.width / (f.channels - 1))
            if subset is None:
                g = grads[key]
                if weights is not None:  # the parameter lets go of its gradient, so the TV adds into it in place
                    dr.eval(g)  # every contribution of the backward pass in first (a resumed fit differed without)
                    dr.disable_grad(self.params[key])
                    g = add_tv_gradient(g, values, f.width, self.neighbours[r], weights)
                g = g + dr.select((channel == 0) & (index < lattice),
                                  sparsity_gradient(values, cfg.sparsity / vertices), 0.0)
                # the empty brick (slot 0) stands for every unallocated brick: it never changes
                g = dr.select(index < f.layout.vertices_per_brick * f.width, 0.0, g)
                if step < self.view_onset():  # progressive view dependence: the mean colour first
                    g = dr.select((index >= lattice) | (channel >= MEAN_CHANNELS), 0.0, g)
            else:
                g = dr.gather(mi.Float, grads[key], subset)
                own = dr.gather(mi.Float, values, subset)
                g = g + dr.select(channel == 0, sparsity_gradient(own, cfg.sparsity / vertices), 0.0)
                if weights is not None:
                    weight = dr.gather(mi.Float, from_numpy(mi.Float, weights), channel)
                    g = g + weight * tv_gradient(values, f.width, self.neighbours[r], subset)
            if self.hull is not None:  # refit only inside the hull (a weight per brick vertex; a view lattice stays)
                vertex = index // f.width
                g = g * dr.gather(mi.Float, self.hull, vertex, index < lattice)
                if self.density_hull is not None:
                    g = dr.select(channel == 0, g * dr.gather(mi.Float, self.density_hull, vertex), g)
            grads[key] = g
        return grads
