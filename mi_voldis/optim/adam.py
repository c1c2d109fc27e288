"""Adam on named Dr.Jit tensors, with per-parameter learning rates and inspectable state.

    m <- b1 m + (1 - b1) g,   v <- b2 v + (1 - b2) g^2,
    x <- x - lr * (m / (1 - b1^t)) / (sqrt(v / (1 - b2^t)) + eps)

The state (m, v, t) is plain arrays so that checkpoints can store and restore it exactly. Parameters
are tensors or flat arrays; a learning rate is a number, or a list of rates applied periodically
along the flat array (one per channel of an interleaved grid, see :mod:`mi_voldis.grid`).
``warmup``: the learning rate ramps up linearly over this many steps after a (re)start, so that the
first, sign-like Adam steps after a grid is resampled do not jolt it. ``scales[key]``, where set: a Float
as wide as the parameter that multiplies its step element by element (learning rates per vertex:
Adam's step is invariant to the scale of a gradient, so scaling the gradient would not do);
``growth[key]``, where set: the same, but only on the steps that increase an element.
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
            if np.ndim(lr):  # per-slot rates, periodic along the array
                slot = dr.arange(mi.UInt32, dr.width(g)) % len(lr)
                step = dr.gather(mi.Float, from_numpy(mi.Float, lr), slot) * step
            else:
                step = lr * step
            if key in self.scales:
                step = self.scales[key] * step
            update = self.m[key] * (step / (dr.sqrt(self.v[key]) + eps))
            if key in self.growth:  # x - update grows where update < 0
                update = dr.select(update < 0.0, update * self.growth[key], update)
            if isinstance(x, mi.TensorXf):
                params[key] = mi.TensorXf(dr.detach(x.array) - update, x.shape)
            else:
                params[key] = dr.detach(x) - update
            dr.schedule(params[key], self.m[key], self.v[key])

    def state(self):
        """{'m/key': array, 'v/key': array} and {'key': t} for checkpoints."""
        arrays = {f"m/{k}": np.array(v) for k, v in self.m.items()}
        arrays.update({f"v/{k}": np.array(v) for k, v in self.v.items()})
        return arrays, dict(self.t)

    def load(self, arrays, t):
        self.reset()
        for key, count in t.items():
            self.m[key] = mi.Float(arrays[f"m/{key}"])
            self.v[key] = mi.Float(arrays[f"v/{key}"])
            self.t[key] = int(count)
