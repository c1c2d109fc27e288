"""The ray-marching loop: primal pass and path-replay adjoint, shared by rendering, fitting and tasks.

A :class:`Plan` fixes what one march computes: which field lookups (field, world -> local matrix),
the composition rule, the layers wanted and the number of samples. The primal pass accumulates,
for every (chain, layer) term of :mod:`mixing`, the sums  sum_i w_i (g_i, k_i, k_i t_i).

Where samples lie (:class:`Path`): in world and NDC space rays are straight and take ``samples``
stratified samples t_i = t0 + (i + u) dt over their interval in the fields' boxes (or as many as fit at
``step``); from a slot in an empty occupancy cell a ray moves to the first slot past that cell, the same
samples in fewer iterations (:meth:`Path.next_slot`). In contracted space rays are curves: the march
steps along the world ray, each step one ``step`` long in scene space
(:meth:`mi_voldis.space.SceneSpace.step_length`), a sample at the fraction u of each step; across cells
the occupancy grid marks empty it takes steps of one cell (``skip``), which cannot cross the one-cell
dilation around occupied cells, so no dense feature is stepped over. A ray stops after ``samples``
evaluated samples there.

The adjoint replays the march front to back (as Mitsuba's PRB integrators do), reading the primal's
sums (evaluated before the replay, with the primal's outputs or its record's writes, so the adjoint's
kernel does not march the primal again), and may replay a batch's rays in another order
(:func:`adjoint_order`: by the primal's iterations per ray, so that a SIMD packet holds rays of like
length; the gradient is the same, summed in another order). The lookups' raw
values at every evaluated sample can be recorded by the primal (:class:`Record`, 16 bytes per sample
and lookup for RGB fields, kept up to RECORD_BYTES): the replay then reads them (one packet a sample)
instead of gathering the 8 grid corners again, and only the gradient scatters touch the grids.
Without a record the replay reads the grids, and memory does not grow with the number of samples.

Primal and adjoint run through one loop body (:func:`march`, as Mitsuba's ``prb_basic.py`` does), and
one driver (:func:`forward`, :func:`backward`) serves ``mi.render`` and the ray batches of fitting.

For a chain with optical depths x_i = sigma_i delta_i and an output L = sum_i w_i g_i with
w_i = exp(-sum_{j<i} x_j) (1 - exp(-x_i)):

    dL/dg_i = w_i,      dL/dx_i = exp(-sum_{j<=i} x_j) g_i - sum_{j>i} w_j g_j.

With the adjoint dL the replay keeps rho = <dL, sum_{j>i} w_j g_j> per chain (initialised from the
primal sums, decremented sample by sample) and back-propagates, per sample,
``<dL, w_i g_i> - rho x_i`` through the field lookups: its gradient is exactly the one above.

A ray also stops early once every chain's optical depth reaches ``stop`` (transmittance below
exp(-stop)); its last sample n then takes all the light left, w_n = exp(-sum_{j<n} x_j)
(:func:`~mi_voldis.render.quadrature.weight_to_stop`), so an opaque surface's alpha is 1, not
1 - exp(-stop). Then dL/dx_n = -sum_{j>n} w_j g_j = 0 and every earlier dL/dx_i keeps the form above
(w_n is exp(-sum_{j<n} x_j) times a factor of x_n alone): the replay, which stops at the same sample,
back-propagates the same ``<dL, w_i g_i> - rho x_i``.

The distortion loss of Mip-NeRF 360 on a chain (samples at path positions s_i, scene units, with
interval lengths delta_i),

    L_dist = sum_i sum_j w_i w_j |s_i - s_j| + 1/3 sum_i w_i^2 delta_i = 2 P + Q / 3,
    P = sum_i w_i (s_i W_<i - S_<i),   Q = sum_i w_i^2 delta_i,   W_<i = sum_{j<i} w_j,  S_<i = sum_{j<i} w_j s_j,

is accumulated by the primal in one pass. Its gradient is that of sum_i w_i a_i with the a_i held
fixed, a_i = dL/dw_i = 2 (2 s_i W_<i - 2 S_<i + S - s_i W) + 2/3 w_i delta_i (W, S: the totals), so the
replay treats it as one more term with colour a_i, and sum_i w_i a_i = 2 L_dist starts its rho.

Near-camera gradient scaling (Philip and Deschaintre, "Floaters No More", 2023), a plan's ``near_grad``
r > 0: the replay multiplies sample i's back-propagated term by min(1, (d_i / r)^2), d_i the world
distance from the ray's origin. A point near a camera covers many of its pixels, so one view's gradient
there outweighs the few other views that see it from afar; the factor evens out that density of
gradients, and the floaters a view grows just in front of itself, which the other views cannot undo,
no longer form. The primal, and so the loss, is unchanged; every term's gradient is scaled alike.
"""
import dataclasses
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from ..device import from_numpy
from ..field.grid import packet_width
from ..transforms import apply_point, apply_vector
from . import mixing, quadrature
from .intervals import sample_interval

COMPONENTS = 5  # per (chain, layer) sum: premultiplied R, G, B, alpha, depth numerator


@dataclass(frozen=True)
class Lookup:
    """One evaluation of a field per sample, at ``to_local`` * p (p in scene space), seen along
    ``to_frame`` * d (d the world direction). ``warp``: a world-space matrix applied to the world
    point before ``to_local`` when the scene space is not world space (where it is folded into
    ``to_local``)."""
    key: str
    field: object
    to_local: np.ndarray
    to_frame: np.ndarray
    warp: np.ndarray | None = None


@dataclass
class Rays:
    """World rays (o, d), their scene-space form (o_s, d_s; in contracted space the normalised ray)
    and the sampled range [t0, t1] of t' (world t in contracted space)."""
    o: object
    d: object
    o_s: object
    d_s: object
    t0: object
    t1: object
    hit: object


@dataclass(frozen=True, eq=False)
class Plan:
    """What one march computes. ``boxes``: world -> unit-cube matrices of every field box that carries
    density, whichever layers are asked for, so that a layer's samples never depend on the others."""
    lookups: tuple
    sources: mixing.Sources
    rule: str
    layers: tuple
    samples: int
    boxes: tuple
    space: object
    occupancy: object = None
    step: float = 0.0  # > 0: samples every ``step`` scene units (at most ``samples`` per ray)
    skip: float = 0.0  # contracted space: the step across empty occupancy cells (scene units)
    distortion: tuple = ()  # layers ("full", "bg") whose chain's distortion loss the march computes
    near: float = 0.0  # world distance from the ray origin where sampling starts
    near_grad: float = 0.0  # > 0: the adjoint scales sample gradients by min(1, (d / near_grad)^2) (docstring)
    stop: float = quadrature.stop_depth(quadrature.STOP_TRANSMITTANCE)  # rays end past this optical depth
    strides: tuple = ()  # contracted space: (occupancy of a STRIDES level, the step below it), sparsest first

    def __post_init__(self):
        # Chains and terms depend only on the rule and layers: find them once with placeholder values.
        dummy = {lk.key: (mi.Float(0.0), mi.Color3f(0.0), mi.Bool(True)) for lk in self.lookups}
        sig, terms = mixing.compose(self.rule, self.sources, self.layers, dummy)
        object.__setattr__(self, "chains", tuple(sig))
        object.__setattr__(self, "terms", tuple(terms))
        roles = {"full": self.sources.full, "bg": self.sources.bg}
        object.__setattr__(self, "distortion_chains", {layer: roles[layer] for layer in self.distortion})

    @property
    def fields(self):
        """Distinct fields of the plan, in lookup order."""
        out = {}
        for lk in self.lookups:
            out.setdefault(id(lk.field), lk.field)
        return list(out.values())


def term_name(chain, layer):
    """Key of a (chain, layer) term in the march's accumulators."""
    return f"{chain}|{layer}"


def prepare_rays(plan, o, d, t_min=0.0, t_max=dr.inf):
    """Scene-space rays and their sampled interval: the union of the plan's boxes, clipped to
    [t_min, t_max] in world space (to [0, 1) of t' in NDC space; in contracted space the world
    interval up to where the contraction reaches ``FAR`` times its inner half-size)."""
    space = plan.space
    if plan.near > 0:
        t_min = dr.maximum(t_min, plan.near)
    if space.is_curved:
        o_n, d_n = space.normalize(o), apply_vector(space.from_world_m, d)
        t0 = dr.maximum(dr.full(mi.Float, 0.0, dr.width(d)), t_min)  # one per ray: records size by it
        t1 = dr.minimum(mi.Float(t_max), _cube_exit(o_n, d_n, FAR))
        return Rays(o, d, o_n, d_n, t0, dr.maximum(t1, t0), t0 < t1)
    o_s, d_s, t_limit = space.ray(o, d)
    if not space.is_world:
        t_min, t_max = 0.0, t_limit
    t0, t1, hit = sample_interval(plan.boxes, o_s, d_s, t_min, t_max)
    occupied = plan.occupancy.bounds() if plan.occupancy is not None else None
    if occupied is not None:  # nothing to evaluate outside the occupied cells' bounds
        t0, t1, hit = sample_interval([occupied], o_s, d_s, t0, t1)
    return Rays(o, d, o_s, d_s, t0, t1, hit)


FAR = 1e4  # contracted space: rays end where ||x_n||_inf = FAR (the contraction is within b 1e-4 of its limit)


def _cube_exit(o, d, m):
    """World t where the normalised ray o + t d leaves the cube [-m, m]^3 (o inside it)."""
    t = mi.Float(dr.inf)
    for a in range(3):
        t = dr.minimum(t, dr.select(d[a] == 0.0, dr.inf, (dr.sign(d[a]) * m - o[a]) / d[a]))
    return t


def sample_count(plan, rays):
    """Straight rays: samples per ray and their spacing dt in t, ``samples`` over [t0, t1], or with a
    ``step`` as many as fit at that scene-space spacing (at least 1, at most ``samples``). Curved rays:
    at most ``samples`` evaluated samples."""
    if plan.space.is_curved:
        return plan.samples, None
    length = rays.t1 - rays.t0
    if plan.step > 0:
        n = dr.clip(mi.UInt32(dr.ceil(length * dr.norm(rays.d_s) / plan.step)), 1, plan.samples)
        return n, length / mi.Float(n)
    return plan.samples, length * (1.0 / plan.samples)


# Contracted rays in occupied cells where every field's optical depth per voxel stays below a level take longer
# steps: (optical depth per voxel, the level's occupancy cells in voxels, the step in voxels), sparsest first.
# A level's cells are marked where density reaches it, dilated by a cell, so a step of at most 0.9 (cell - voxel)
# from an unmarked cell never reaches density above it; the step never falls below the march's own. Levels chosen
# on the captures' fits, what they save and cost: reports/notes.md ("Longer steps through thin cells").
STRIDES = ((0.03, 8, 6.3), (0.3, 4, 2.0), (3.0, 4, 1.0))


class Path:
    """Where the samples of a batch of rays lie (module docstring): ``sample(i, b)`` gives sample i's
    scene point p, world distance t, scene-space interval length delta, whether it lies in an
    occupied cell, its position s along the path (scene units), and the next ``b`` (curved rays: the
    world t and the path position where the next step starts)."""

    def __init__(self, plan, rays, u):
        self.plan, self.rays, self.u = plan, rays, u
        self.n, self.dt = sample_count(plan, rays)
        if not plan.space.is_curved:
            self.delta = self.dt * dr.norm(rays.d_s)

    def start(self):
        if not self.plan.space.is_curved:
            return mi.UInt32(0)
        return mi.Float(self.rays.t0), mi.Float(0.0)

    def sample(self, i, b):
        plan, rays, space = self.plan, self.rays, self.plan.space
        if not space.is_curved:  # b: the slot j, sample t0 + (j + u) dt
            t = rays.t0 + (mi.Float(b) + self.u) * self.dt
            p = rays.o_s + t * rays.d_s
            occupied = plan.occupancy.lookup(p) if plan.occupancy is not None else mi.Bool(True)
            return (p, _distance(plan, rays, t, p), self.delta, occupied, (mi.Float(b) + self.u) * self.delta,
                    self.next_slot(b, t, p, occupied))
        t_b, s_b = b
        x = rays.o_s + t_b * rays.d_s
        xc = space.contract(x)
        occupied = plan.occupancy.lookup(xc) if plan.occupancy is not None else mi.Bool(True)
        step = dr.select(occupied, plan.step, plan.skip) if plan.occupancy is not None else mi.Float(plan.step)
        if plan.strides:  # an occupied cell thin at some level (the sparsest first) is crossed in its longer steps
            chosen = ~occupied
            for grid, level_step in plan.strides:
                take = ~chosen & ~grid.lookup(xc)
                step = dr.select(take, level_step, step)
                chosen |= take
        dt = step / space.step_length(x, rays.d_s)
        t = t_b + self.u * dt
        return (space.contract(rays.o_s + t * rays.d_s), t, step, occupied, s_b + self.u * step,
                (t_b + dt, s_b + step))

    def next_slot(self, j, t, p, occupied):
        """Straight rays: the slot after slot ``j`` (at ray parameter ``t``, scene point ``p``), past the
        rest of an unoccupied cell: its slots would be skipped one by one, every one unevaluated, so
        jumping over them gives the same samples in fewer loop iterations. The first slot at or beyond
        the cell's exit t_x is ceil((t_x - t0) / dt - u); SLOT_EPS of a slot less, so that rounding can
        only land a slot back in the empty cell (skipped again), never past one of the next cell."""
        following = j + 1
        occupancy = self.plan.occupancy
        if occupancy is None:
            return following
        rays = self.rays
        exit = t + occupancy.exit_distance(p, rays.d_s)
        beyond = dr.ceil((exit - rays.t0) / self.dt - self.u - SLOT_EPS)
        jump = ~occupied & (self.dt > 0.0) & dr.isfinite(beyond) & (beyond > mi.Float(following))
        return dr.select(jump, mi.UInt32(dr.minimum(beyond, mi.Float(self.n))), following)

    def more(self, i, k, b):
        """Whether samples remain after ``i`` samples of which ``k`` were evaluated, next start ``b``
        (straight rays: the next slot)."""
        if self.plan.space.is_curved:
            return (b[0] < self.rays.t1) & (k < self.n)
        return b < self.n


def _distance(plan, rays, t, p):
    """World distance along the ray of the scene-space point ``p`` = o' + t d'."""
    if plan.space.is_world:
        return t
    return dr.dot(plan.space.to_world(p) - rays.o, rays.d)


def _sample(plan, data, p, d, active, raw=None):
    """Chains' densities and the terms at scene-space points ``p`` seen along world directions ``d``,
    where ``active`` (elsewhere every density is 0).

    ``raw``: the lookups' raw values at these points, recorded by the primal (:class:`Record`), or
    None. Given, the lookups take their values from it and read nothing from the grids: only their
    gradients go there (their gathers have no use left and drop out of the kernel)."""
    values, lookups = {}, {}
    for lk in plan.lookups:
        q = p if lk.warp is None else plan.space.from_world(apply_point(lk.warp, plan.space.to_world(p)))
        pl = apply_point(lk.to_local, q)
        inside = active & dr.all((pl >= 0.0) & (pl <= 1.0))
        v = lk.field.lookup(pl, data[id(lk.field)], inside)
        if raw is not None:
            v = [dr.replace_grad(r, x) for r, x in zip(raw[lk.key], v)]
        lookups[lk.key] = v
        values[lk.key] = (*lk.field.activate(v, apply_vector(lk.to_frame, d), inside), inside)
    sig, terms = mixing.compose(plan.rule, plan.sources, plan.layers, values)
    return sig, terms, lookups


class Record:
    """The raw values of every lookup at every evaluated sample of a primal march, for its adjoint to
    replay instead of reading the grids again. The k-th evaluated sample of ray r sits at slot
    k * rays + r, so that a SIMD packet of neighbouring rays writes one contiguous run; ``index``: the ray
    each lane reads (the adjoint's order); ``samples``: the most any ray evaluates."""

    def __init__(self, plan, rays, samples):
        self.rays = rays
        self.index = dr.arange(mi.UInt32, rays)
        self.fields = {lk.key: lk.field for lk in plan.lookups}
        self.widths = {key: packet_width(f.lookup_channels) for key, f in self.fields.items()}
        self.buffers = {key: dr.empty(mi.Float, self.widths[key] * rays * samples) for key in self.fields}
        dr.eval(self.buffers)

    @staticmethod
    def size(plan, rays, samples):
        """Bytes a record of ``rays`` rays and ``samples`` samples per ray takes."""
        return 4 * rays * samples * sum(packet_width(lk.field.lookup_channels) for lk in plan.lookups)

    def _slot(self, i):
        return i * self.rays + self.index

    def write(self, i, lookups, active):
        for key, buf in self.buffers.items():
            v = list(lookups[key]) + [mi.Float(0.0)] * (self.widths[key] - len(lookups[key]))
            dr.scatter(buf, mi.ArrayXf(v), self._slot(i), active)

    def read(self, i, active):
        out = {}
        for key, buf in self.buffers.items():
            v = dr.gather(mi.ArrayXf, buf, self._slot(i), active, shape=(self.widths[key], self.rays))
            out[key] = [v[k] for k in range(self.fields[key].lookup_channels)]
        return out


def _transparent(depth, stop):
    """Some chain's optical depth is still below ``stop``, i.e. its transmittance above exp(-stop): it
    is transparent enough to matter (early termination)."""
    lowest = None
    for s in depth.values():
        lowest = s if lowest is None else dr.minimum(lowest, s)
    return lowest < stop


def march(mode, plan, data, rays, u, active, record=None, grads=None, acc=None, probe=None):
    """The march over a batch of rays, primal or adjoint, through one loop body.

    ``mode`` ``dr.ADMode.Primal``: returns ``(acc, stats)``: {"chain|layer": [R, G, B, alpha,
    depth-numerator]} (Float arrays) and per-ray statistics (not differentiable): ``evaluated``, the
    samples evaluated (occupied and before termination), and with the ``fg`` layer ``fg_coverage`` =
    sum_i max(w_fg,i, 0), how much of the ray the object covers (sum_i w_fg,i = alpha_full - alpha_bg
    vanishes wherever an opaque background lies behind the object). A ``record`` keeps the lookups'
    raw values.

    ``mode`` ``dr.ADMode.Backward``: the path-replay adjoint; accumulates gradients into the
    (gradient-tracked) arrays of ``data``. ``grads``: layer -> (dRGB Color3f, d_alpha,
    d_depth_numerator), the adjoint of each layer's raw sums; ``acc``: the primal's sums for the same
    rays and jitter; ``record``: the primal's :class:`Record`, if it kept one (the replay then reads
    no grid values).

    ``data``: id(field) -> packed grid; ``rays``: from :func:`prepare_rays`; ``u``: per-ray jitter
    in [0, 1) of the samples (see :class:`Path`); ``probe(p, w, active, depth)``: called by the primal with
    every sample's scene point, chains' weights and optical depths before it (e.g. to find where
    rays end)."""
    primal = mode == dr.ADMode.Primal
    path = Path(plan, rays, u)
    zero = dr.zeros(mi.Float, dr.width(rays.t0))
    depth = {c: mi.Float(zero) for c in plan.chains}
    fg_chains = (plan.sources.full_q, plan.sources.bg_q) if "fg" in plan.layers else None
    if primal:  # loop state: the sums and the statistics
        sums = {term_name(*k): [mi.Float(zero) for _ in range(COMPONENTS)] for k in plan.terms}
        sums.update({dist_name(c): [mi.Float(zero) for _ in range(4)] for c in plan.distortion_chains.values()})
        carry = (sums, {"evaluated": mi.Float(zero), "fg_coverage": mi.Float(zero)})
    else:  # loop state: rho = <dL, sum_{j>i} w_j g_j> per chain, from the primal's sums
        rho = {c: mi.Float(zero) for c in plan.chains}
        for chain, layer in plan.terms:
            g_rgb, g_a, g_d = grads[layer]
            a = acc[term_name(chain, layer)]
            rho[chain] += g_rgb[0] * a[0] + g_rgb[1] * a[1] + g_rgb[2] * a[2] + g_a * a[3] + g_d * a[4]
        for layer, c in plan.distortion_chains.items():  # sum_i w_i a_i = 2 L_dist
            rho[c] += grads["distortion"][layer] * 2.0 * distortion_value(acc[dist_name(c)])
        # and the running sums W_<i, S_<i of each distortion chain
        carry = (rho, {c: (mi.Float(zero), mi.Float(zero)) for c in plan.distortion_chains.values()})

    def body(i, k, b, active, depth, carry):
        p, t, delta, occupied, s, b = path.sample(i, b)
        evaluate = active & occupied
        with dr.resume_grad(when=not primal):
            raw = record.read(k, evaluate) if record is not None and not primal else None
            sig, terms, lookups = _sample(plan, data, p, rays.d, evaluate, raw)
            x = {c: sig[c] * delta for c in plan.chains}
            after = {c: depth[c] + dr.detach(x[c]) for c in plan.chains}
            last = ~_transparent(after, plan.stop)  # the ray stops after this sample: it takes what is left
            w = {c: quadrature.weight_to_stop(depth[c], x[c], last) for c in plan.chains}
            if primal:
                carry = _accumulate(plan, carry, terms, w, t, evaluate, fg_chains, s, delta)
                if record is not None:
                    record.write(k, lookups, evaluate)
                if probe is not None:
                    probe(p, w, evaluate, depth)
            else:
                scale = None if not plan.near_grad else near_scale(t, plan.near_grad)
                carry = _backpropagate(plan, carry, terms, w, x, t, grads, active, s, delta, acc, scale)
        i, k = i + 1, k + dr.select(evaluate, 1, 0)
        return i, k, b, active & path.more(i, k, b) & ~last, after, carry

    state = (mi.UInt32(0), mi.UInt32(0), path.start(), mi.Bool(active) & rays.hit, depth, carry)
    iterations, *_, carry = dr.while_loop(state, lambda i, k, b, a, *_: a, body,
                                          label="voldis primal" if primal else "voldis adjoint")
    if primal:
        carry[1]["iterations"] = iterations
    return carry if primal else None


def dist_name(chain):
    return f"dist|{chain}"


def distortion_value(sums):
    """L_dist = 2 P + Q / 3 from a chain's distortion sums [W, S, P, Q] (module docstring)."""
    return 2.0 * sums[2] + sums[3] * (1.0 / 3.0)


def _accumulate(plan, carry, terms, w, t, occupied, fg_chains, s, delta):
    """Primal step: add sample i's w (g, k, k t) to every term's sums and its distortion terms; count
    the sample."""
    acc, stats = dict(carry[0]), dict(carry[1])
    for (chain, layer), (g, k) in terms.items():
        a = acc[term_name(chain, layer)]
        wk = w[chain] * k
        acc[term_name(chain, layer)] = [dr.fma(w[chain], g[0], a[0]), dr.fma(w[chain], g[1], a[1]),
                                         dr.fma(w[chain], g[2], a[2]), a[3] + wk, dr.fma(wk, t, a[4])]
    for c in plan.distortion_chains.values():
        big_w, big_s, p, q = acc[dist_name(c)]
        wc = w[c]
        acc[dist_name(c)] = [big_w + wc, dr.fma(wc, s, big_s), dr.fma(wc, s * big_w - big_s, p),
                              dr.fma(wc * wc, delta, q)]
    stats["evaluated"] = stats["evaluated"] + dr.select(occupied, 1.0, 0.0)
    if fg_chains is not None and fg_chains[0] != fg_chains[1]:
        stats["fg_coverage"] = stats["fg_coverage"] + dr.maximum(w[fg_chains[0]] - w[fg_chains[1]], 0.0)
    return acc, stats


def near_scale(distance, near_grad):
    """The near-camera factor min(1, (d / near_grad)^2) of a sample at world distance ``d`` (module
    docstring)."""
    return dr.minimum(1.0, dr.square(distance * (1.0 / near_grad)))


def _backpropagate(plan, carry, terms, w, x, t, grads, active, s, delta, acc, scale=None):
    """Adjoint step: back-propagate <dL, w_i g_i> - rho x_i of every chain through sample i's lookups
    (its gradient is dL/dg_i and dL/dx_i of the module docstring; the distortion loss a term with
    colour a_i), times ``scale`` (the near-camera factor, None: 1), and move rho and the distortion's
    running sums past sample i."""
    rho, running = dict(carry[0]), dict(carry[1])
    value = {c: mi.Float(0.0) for c in plan.chains}
    for (chain, layer), (g, k) in terms.items():
        g_rgb, g_a, g_d = grads[layer]
        value[chain] += w[chain] * (dr.dot(g_rgb, g) + k * dr.fma(g_d, t, g_a))
    for layer, c in plan.distortion_chains.items():
        big_w, big_s = acc[dist_name(c)][:2]
        w_before, s_before = running[c]
        wc = dr.detach(w[c])
        a = 2.0 * (2.0 * (s * w_before - s_before) + big_s - s * big_w) + (2.0 / 3.0) * wc * delta
        value[c] += grads["distortion"][layer] * w[c] * a
        running[c] = (w_before + wc, dr.fma(wc, s, s_before))
    objective = mi.Float(0.0)
    for c in plan.chains:
        rho[c] = rho[c] - dr.detach(value[c])
        objective += value[c] - rho[c] * x[c]
    if scale is not None:
        objective = objective * dr.detach(scale)
    # AllowNoGrad: a tracked field may receive nothing (its layers absent from the loss)
    dr.backward_from(dr.select(active & dr.isfinite(objective), objective, 0.0),
                     flags=dr.ADFlag.Default | dr.ADFlag.AllowNoGrad)
    return rho, running


SLOT_EPS = 1e-3  # of a slot: the margin by which a straight ray's jump past an empty cell falls short

RECORD_BYTES = 1 << 30  # largest Record kept; larger batches replay by reading the grids again (0: never)


def new_record(plan, rays):
    """A :class:`Record` for a primal march of ``rays``, or None if it would exceed RECORD_BYTES."""
    n, _ = sample_count(plan, rays)
    most = n if isinstance(n, int) else int(dr.max(n)[0])
    count = dr.width(rays.t0)
    if Record.size(plan, count, most) > RECORD_BYTES:
        return None
    return Record(plan, count, most)


@dataclass
class Forward:
    """What a primal march leaves for its adjoint: the rays, jitter, the sums and the record."""
    plan: Plan
    rays: Rays
    u: object
    active: object
    acc: dict
    stats: dict
    record: Record | None
    order: object = None  # the rays' order for the adjoint (:func:`adjoint_order`); None: as marched


def forward(plan, rays, u, active=True, keep_record=False, probe=None):
    """Primal march of ``rays`` (from :func:`prepare_rays`) over the fields' current values; with
    ``keep_record`` the lookups' raw values are kept (when they fit RECORD_BYTES) for
    :func:`backward`; ``probe``: see :func:`march`."""
    record = new_record(plan, rays) if keep_record else None
    data = {id(f): dr.detach(f.packed) for f in plan.fields}
    acc, stats = march(dr.ADMode.Primal, plan, data, rays, u, active, record, probe=probe)
    return Forward(plan, rays, u, active, acc, stats, record)


def adjoint_order(iterations):
    """The order (NumPy indices) in which the adjoint replays a batch's rays: by the primal's loop
    iterations per ray. A SIMD packet of rays loops until its longest ray ends, so rays of like length
    side by side waste fewer lanes (reports/notes.md, 2026-12-07)."""
    return np.argsort(np.asarray(iterations), kind="stable")


def _reordered(fwd, grads):
    """The adjoint's inputs (rays, jitter, active, primal sums, layer adjoints) in ``fwd.order``, and the
    record reading each ray's own slots."""
    index = from_numpy(mi.UInt32, fwd.order.astype(np.uint32))

    def take(x):
        if isinstance(x, (tuple, list)):
            return type(x)(take(v) for v in x)
        if isinstance(x, dict):
            return {k: take(v) for k, v in x.items()}
        if not dr.is_array_v(x) or dr.width(x) <= 1:  # a constant over the batch
            return x
        if dr.depth_v(x) > 1:
            return type(x)(*(take(c) for c in x))
        return dr.gather(type(x), x, index)

    rays = Rays(*(take(getattr(fwd.rays, f.name)) for f in dataclasses.fields(Rays)))
    if fwd.record is not None:
        fwd.record.index = index
    return rays, take(fwd.u), take(fwd.active), take(fwd.acc), take(grads)


def backward(fwd, grads):
    """Gradients of the fields' packed grids, ``{id(field): array or None}``, from the adjoint march
    of a :class:`Forward` with layer adjoints ``grads`` (see :func:`march`); frees its record.

    The march writes into detached, gradient-tracked copies of the packed grids (of the fields whose
    ``packed`` array tracks gradients), so the AD traversal inside the loop stops there; callers hand
    the result on to the fields' parameters."""
    plan = fwd.plan
    # The primal's sums, evaluated with its record's writes in one kernel (a no-op where the caller evaluated
    # them with its outputs): left lazy, the adjoint's kernel would march the primal again to get them.
    dr.eval(fwd.acc)
    with dr.resume_grad():
        leaves = {}
        for f in plan.fields:
            leaf = dr.detach(f.packed)
            if dr.grad_enabled(f.packed):
                dr.enable_grad(leaf)
            leaves[id(f)] = leaf
        # Gradient scatters into arrays above the expand threshold silently fall back to atomics
        # (several times slower on CPUs): raise the threshold to cover the grids.
        largest = max(dr.width(leaf) for leaf in leaves.values())
        if dr.expand_threshold() <= largest:
            dr.set_expand_threshold(largest + 1)
        rays, u, active, acc = fwd.rays, fwd.u, fwd.active, fwd.acc
        if fwd.order is not None:
            rays, u, active, acc, grads = _reordered(fwd, grads)
        march(dr.ADMode.Backward, plan, leaves, rays, u, active, fwd.record, grads, acc)
        fwd.record = None
        return {k: dr.grad(v) if dr.grad_enabled(v) else None for k, v in leaves.items()}
