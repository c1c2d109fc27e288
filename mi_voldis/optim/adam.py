"""Adam on named Dr.Jit tensors, with per-parameter learning rates and inspectable state.

    m <- b1 m + (1 - b1) g,   v <- b2 v + (1 - b2) g^2,
    x <- x - lr * (m / (1 - b1^t)) / (sqrt(v / (1 - b2^t)) + eps)

The state (m, v, t) is plain arrays so that checkpoints can store and restore it exactly. Parameters
are tensors or flat arrays; a learning rate is a number, or a list of rates applied periodically
along the flat array (one per channel of an interleaved grid, see :mod:`mi_voldis.field.grid`).
``warmup``: the learning rate ramps up linearly over this many steps after a (re)start, so that the
first, sign-like Adam steps after a grid is resampled do not jolt it. ``scales[key]``, where set: a Float
as wide as the parameter that multiplies its step element by element (learning rates per vertex:
Adam's step is invariant to the scale of a gradient, so scaling the gradient would not do);
``growth[key]``, where set: the same, but only on the steps that increase an element.
``subsets[key]``, where set: the UInt32 indices of the only elements that may change (a refit inside a
region): the moments are kept for them alone and ``grads[key]`` holds the gradient at them, in their order.
Elements whose gradient is always zero never move under Adam (their moments stay zero), so this steps
exactly as the whole array with the gradient masked to the subset would, on memory and time of its size.
``holds[key]``, where set: (UInt32 indices, value): those elements are written with the value after every
step (a projection onto a constraint, e.g. space kept empty). Written into the step's own new array, so
the hold costs its indices alone; the same write made after the step, on an array the parameters and the
fields both reference, would copy the whole array first.
"""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..device import from_numpy


class Adam:
    def __init__(self, lrs, beta1=0.9, beta2=0.99, eps=1e-8, warmup=0):
        self.lrs = dict(lrs)
        self.beta1, self.beta2, self.eps, self.warmup = beta1, beta2, eps, warmup
        self.m, self.v, self.t = {}, {}, {}
        self.scales = {}  # key -> Float: per-element factors on the step (they follow the lattice, not the moments)
        self.growth = {}  # key -> Float: per-element factors on the steps that increase an element
        self.subsets = {}  # key -> UInt32: the elements stepped, the gradient given at them alone
        self.holds = {}  # key -> (UInt32, float): elements set to the value after each step

    def reset(self, key=None):
        """Forget the moments (of one parameter, or all): e.g. after a grid is resampled."""
        for store in (self.m, self.v, self.t):
            if key is None:
                store.clear()
            else:
                store.pop(key, None)

    def step(self, params, grads, scale=1.0):
        """Update ``params[key]`` (TensorXf or Float) with ``grads[key]`` (flat Float) for every key
        with a learning rate; ``scale`` multiplies every learning rate (schedules)."""
        for key, lr in self.lrs.items():
            if not np.any(lr) or key not in grads or grads[key] is None:
                continue
            x = params[key]
            g = dr.detach(grads[key])
            subset = self.subsets.get(key)
            if subset is not None and dr.width(subset) == 0:  # nothing may change
                continue
            if key not in self.m or dr.width(self.m[key]) != dr.width(g):
                # opaque zeros: the first update then runs the same kernel as every later one
                self.m[key], self.v[key] = dr.opaque(mi.Float, 0.0, dr.width(g)), dr.opaque(mi.Float, 0.0, dr.width(g))
                self.t[key] = 0
            self.t[key] += 1
            t = self.t[key]
            self.m[key] = dr.fma(self.beta1, self.m[key], (1 - self.beta1) * g)
            self.v[key] = dr.fma(self.beta2, self.v[key], (1 - self.beta2) * dr.square(g))
            ramp = min(1.0, t / self.warmup) if self.warmup else 1.0
            # numbers that change every step enter as arrays, not as constants compiled into the
            # kernel: else the update kernel would compile anew at every step
            step = dr.opaque(mi.Float, scale * ramp * np.sqrt(1 - self.beta2 ** t) / (1 - self.beta1 ** t))
            eps = dr.opaque(mi.Float, self.eps * np.sqrt(1 - self.beta2 ** t))
            index = dr.arange(mi.UInt32, dr.width(g)) if subset is None else subset
            if np.ndim(lr):  # per-slot rates, periodic along the array
                step = dr.gather(mi.Float, from_numpy(mi.Float, lr), index % len(lr)) * step
            else:
                step = lr * step
            if key in self.scales:
                step = self._at(self.scales[key], subset) * step
            update = self.m[key] * (step / (dr.sqrt(self.v[key]) + eps))
            if key in self.growth:  # x - update grows where update < 0
                update = dr.select(update < 0.0, update * self._at(self.growth[key], subset), update)
            flat = dr.detach(x.array if isinstance(x, mi.TensorXf) else x)
            if subset is None:
                flat = flat - update
            else:  # the stepped elements first, then written into a copy of the array
                stepped = dr.gather(mi.Float, flat, subset) - update
                dr.eval(stepped, self.m[key], self.v[key])
                flat = mi.Float(flat)
                dr.scatter(flat, stepped, subset)
            if key in self.holds:
                held, value = self.holds[key]
                dr.eval(flat, self.m[key], self.v[key])  # a new array that nothing else references: written in place
                dr.scatter(flat, value, held)
            params[key] = mi.TensorXf(flat, x.shape) if isinstance(x, mi.TensorXf) else flat
            dr.schedule(params[key], self.m[key], self.v[key])

    @staticmethod
    def _at(values, subset):
        """Per-element ``values`` at the stepped elements (all of them without a ``subset``)."""
        return values if subset is None else dr.gather(mi.Float, values, subset)

    def state(self):
        """{'m/key': array, 'v/key': array} and {'key': t} for checkpoints: views of the moments' buffers
        (valid until the next step replaces them), not copies."""
        arrays = {f"m/{k}": np.asarray(v) for k, v in self.m.items()}
        arrays.update({f"v/{k}": np.asarray(v) for k, v in self.v.items()})
        return arrays, dict(self.t)

    def load(self, arrays, t):
        self.reset()
        for key, count in t.items():
            self.m[key] = mi.Float(arrays[f"m/{key}"])
            self.v[key] = mi.Float(arrays[f"v/{key}"])
            self.t[key] = int(count)
