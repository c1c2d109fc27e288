"""The ray-marching loop: primal pass and path-replay adjoint, shared by rendering, fitting and tasks.

A :class:`Plan` fixes what one march computes: which field lookups (field, world -> local matrix),
the composition rule, the layers wanted and the number of samples. The primal pass accumulates,
for every (chain, layer) term of :mod:`mixing`, the sums  sum_i w_i (g_i, k_i, k_i t_i).

The adjoint replays the march front to back (as Mitsuba's PRB integrators do). The lookups' raw
values at every sample can be recorded by the primal (:class:`Record`, 16 bytes per sample and
lookup for RGB fields, kept up to RECORD_BYTES): the replay then reads them in contiguous runs
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
"""
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

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
    """World rays (o, d), their scene-space form (o_s, d_s) and the sampled range [t0, t1] of t'."""
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

    def __post_init__(self):
        # Chains and terms depend only on the rule and layers: find them once with placeholder values.
        dummy = {lk.key: (mi.Float(0.0), mi.Color3f(0.0), mi.Bool(True)) for lk in self.lookups}
        sig, terms = mixing.compose(self.rule, self.sources, self.layers, dummy)
        object.__setattr__(self, "chains", tuple(sig))
        object.__setattr__(self, "terms", tuple(terms))

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
    [t_min, t_max] in world space (to [0, 1) of t' in NDC space)."""
    o_s, d_s, t_limit = plan.space.ray(o, d)
    if not plan.space.is_world:
        t_min, t_max = 0.0, t_limit
    t0, t1, hit = sample_interval(plan.boxes, o_s, d_s, t_min, t_max)
    occupied = plan.occupancy.bounds() if plan.occupancy is not None else None
    if occupied is not None:  # nothing to evaluate outside the occupied cells' bounds
        t0, t1, hit = sample_interval([occupied], o_s, d_s, t0, t1)
    return Rays(o, d, o_s, d_s, t0, t1, hit)


def sample_count(plan, rays):
    """Samples per ray and their spacing dt in t: ``samples`` over [t0, t1], or with a ``step`` as many
    as fit at that scene-space spacing (at least 1, at most ``samples``)."""
    length = rays.t1 - rays.t0
    if plan.step > 0:
        n = dr.clip(mi.UInt32(dr.ceil(length * dr.norm(rays.d_s) / plan.step)), 1, plan.samples)
        return n, length / mi.Float(n)
    return plan.samples, length * (1.0 / plan.samples)


def _distance(plan, rays, t, p):
    """World distance along the ray of the scene-space point ``p`` = o' + t d'."""
    if plan.space.is_world:
        return t
    return dr.dot(plan.space.to_world(p) - rays.o, rays.d)


def _sample(plan, data, p, d, active, raw=None):
    """Chains' densities and the terms at scene-space points ``p`` seen along world directions ``d``.
    Samples in unoccupied cells are not evaluated (every density is 0 there).

    ``raw``: the lookups' raw values at these points, recorded by the primal (:class:`Record`), or
    None. Given, the lookups take their values from it and read nothing from the grids: only their
    gradients go there (their gathers have no use left and drop out of the kernel)."""
    if plan.occupancy is not None:
        active = active & plan.occupancy.lookup(p)
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
    return sig, terms, active, lookups


class Record:
    """The raw values of every lookup at every sample of a primal march, for its adjoint to replay
    instead of reading the grids again. Sample i of ray r sits at slot i * rays + r, so that a SIMD
    packet of neighbouring rays writes and reads one contiguous run; ``samples``: the most any ray
    takes."""

    def __init__(self, plan, rays, samples):
        self.rays = rays
        self.index = dr.arange(mi.UInt32, rays)
        self.fields = {lk.key: lk.field for lk in plan.lookups}
        self.buffers = {key: dr.empty(mi.Float, f.width * rays * samples) for key, f in self.fields.items()}
        dr.eval(self.buffers)

    @staticmethod
    def size(plan, rays, samples):
        """Bytes a record of ``rays`` rays and ``samples`` samples per ray takes."""
        return 4 * rays * samples * sum(lk.field.width for lk in plan.lookups)

    def _slot(self, i):
        return i * self.rays + self.index

    def write(self, i, lookups, active):
        for key, buf in self.buffers.items():
            v = list(lookups[key]) + [mi.Float(0.0)] * (self.fields[key].width - len(lookups[key]))
            dr.scatter(buf, mi.ArrayXf(v), self._slot(i), active)

    def read(self, i, active):
        out = {}
        for key, buf in self.buffers.items():
            f = self.fields[key]
            v = dr.gather(mi.ArrayXf, buf, self._slot(i), active, shape=(f.width, self.rays))
            out[key] = [v[k] for k in range(f.channels)]
        return out


def _continue(i, depth, n):
    """Keep marching while samples remain and some chain is still transparent enough to matter."""
    lowest = None
    for s in depth.values():
        lowest = s if lowest is None else dr.minimum(lowest, s)
    return (i < n) & (lowest < quadrature.OPTICAL_DEPTH_CUTOFF)


def march(mode, plan, data, rays, u, active, record=None, grads=None, acc=None):
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
    in [0, 1) of the stratified samples t_i = t0 + (i + u) dt (see :func:`sample_count`)."""
    primal = mode == dr.ADMode.Primal
    n, dt = sample_count(plan, rays)
    delta = dt * dr.norm(rays.d_s)
    zero = dr.zeros(mi.Float, dr.width(rays.t0))
    depth = {c: mi.Float(zero) for c in plan.chains}
    fg_chains = (plan.sources.full_q, plan.sources.bg_q) if "fg" in plan.layers else None
    if primal:  # loop state: the sums and the statistics
        carry = ({term_name(*k): [mi.Float(zero) for _ in range(COMPONENTS)] for k in plan.terms},
                 {"evaluated": mi.Float(zero), "fg_coverage": mi.Float(zero)})
    else:  # loop state: rho = <dL, sum_{j>i} w_j g_j> per chain, from the primal's sums
        carry = {c: mi.Float(zero) for c in plan.chains}
        for chain, layer in plan.terms:
            g_rgb, g_a, g_d = grads[layer]
            a = acc[term_name(chain, layer)]
            carry[chain] += g_rgb[0] * a[0] + g_rgb[1] * a[1] + g_rgb[2] * a[2] + g_a * a[3] + g_d * a[4]

    def body(i, active, depth, carry):
        t = rays.t0 + (mi.Float(i) + u) * dt
        p = rays.o_s + t * rays.d_s
        with dr.resume_grad(when=not primal):
            raw = record.read(i, active) if record is not None and not primal else None
            sig, terms, occupied, lookups = _sample(plan, data, p, rays.d, active, raw)
            t = _distance(plan, rays, t, p)
            x = {c: sig[c] * delta for c in plan.chains}
            w = {c: quadrature.weight(depth[c], x[c]) for c in plan.chains}
            if primal:
                carry = _accumulate(plan, carry, terms, w, t, occupied, fg_chains)
                if record is not None:
                    record.write(i, lookups, active)
            else:
                carry = _backpropagate(plan, carry, terms, w, x, t, grads, active)
        depth = {c: depth[c] + dr.detach(x[c]) for c in plan.chains}
        i = i + 1
        return i, active & _continue(i, depth, n), depth, carry

    state = (mi.UInt32(0), mi.Bool(active) & rays.hit, depth, carry)
    _, _, _, carry = dr.while_loop(state, lambda i, a, *_: a, body,
                                   label="voldis primal" if primal else "voldis adjoint")
    return carry if primal else None


def _accumulate(plan, carry, terms, w, t, occupied, fg_chains):
    """Primal step: add sample i's w (g, k, k t) to every term's sums; count the sample."""
    acc, stats = dict(carry[0]), dict(carry[1])
    for (chain, layer), (g, k) in terms.items():
        a = acc[term_name(chain, layer)]
        wk = w[chain] * k
        acc[term_name(chain, layer)] = [dr.fma(w[chain], g[0], a[0]), dr.fma(w[chain], g[1], a[1]),
                                         dr.fma(w[chain], g[2], a[2]), a[3] + wk, dr.fma(wk, t, a[4])]
    stats["evaluated"] = stats["evaluated"] + dr.select(occupied, 1.0, 0.0)
    if fg_chains is not None and fg_chains[0] != fg_chains[1]:
        stats["fg_coverage"] = stats["fg_coverage"] + dr.maximum(w[fg_chains[0]] - w[fg_chains[1]], 0.0)
    return acc, stats


def _backpropagate(plan, rho, terms, w, x, t, grads, active):
    """Adjoint step: back-propagate <dL, w_i g_i> - rho x_i of every chain through sample i's lookups
    (its gradient is dL/dg_i and dL/dx_i of the module docstring) and move rho past sample i."""
    value = {c: mi.Float(0.0) for c in plan.chains}
    for (chain, layer), (g, k) in terms.items():
        g_rgb, g_a, g_d = grads[layer]
        value[chain] += w[chain] * (dr.dot(g_rgb, g) + k * dr.fma(g_d, t, g_a))
    rho = dict(rho)
    objective = mi.Float(0.0)
    for c in plan.chains:
        rho[c] = rho[c] - dr.detach(value[c])
        objective += value[c] - rho[c] * x[c]
    dr.backward_from(dr.select(active & dr.isfinite(objective), objective, 0.0))
    return rho


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


def forward(plan, rays, u, active=True, keep_record=False):
    """Primal march of ``rays`` (from :func:`prepare_rays`) over the fields' current values; with
    ``keep_record`` the lookups' raw values are kept (when they fit RECORD_BYTES) for
    :func:`backward`."""
    record = new_record(plan, rays) if keep_record else None
    data = {id(f): dr.detach(f.packed) for f in plan.fields}
    acc, stats = march(dr.ADMode.Primal, plan, data, rays, u, active, record)
    return Forward(plan, rays, u, active, acc, stats, record)


def backward(fwd, grads):
    """Gradients of the fields' packed grids, ``{id(field): array or None}``, from the adjoint march
    of a :class:`Forward` with layer adjoints ``grads`` (see :func:`march`); frees its record.

    The march writes into detached, gradient-tracked copies of the packed grids (of the fields whose
    ``packed`` array tracks gradients), so the AD traversal inside the loop stops there; callers hand
    the result on to the fields' parameters."""
    plan = fwd.plan
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
        march(dr.ADMode.Backward, plan, leaves, fwd.rays, fwd.u, fwd.active, fwd.record, grads, fwd.acc)
        fwd.record = None
        return {k: dr.grad(v) if dr.grad_enabled(v) else None for k, v in leaves.items()}
