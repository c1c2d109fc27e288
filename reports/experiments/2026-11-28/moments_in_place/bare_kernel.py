"""Adam's update as bare kernels on 45 M floats, two rounds in turns: out of place ("oop": values and moments as
three new arrays), the moments scattered in place through views of their memory ("flat"), and the same in
packets of 4 floats a lane ("packet"). The median of steps 3-6 in ms and the last value (the arrays carry
over from kind to kind: not a check) (reports/notes.md, 2026-11-28: these
bare kernels do not show the optimiser's in-place slowdown, which is not yet explained).

    python reports/experiments/2026-11-28/moments_in_place/bare_kernel.py oop flat packet
"""
import sys
import time

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("llvm_ad_rgb")


def memory_view(array):
    """A second Dr.Jit variable over ``array``'s memory (zero-copy import), as adam_in_place.diff reads it."""
    dr.eval(array)
    return mi.Float(dr.detail.import_tensor(array, False).array)


N = 45_000_000


def fresh(s):
    a = dr.arange(mi.Float, N) * s
    dr.eval(a)
    return a


x, m, v, g = fresh(1e-9), fresh(1e-10), fresh(1e-11), fresh(2e-9)
lr = mi.Float([0.1, 0.05, 0.05, 0.05])


def oop(x, m, v):
    m = dr.fma(0.9, m, 0.1 * g)
    v = dr.fma(0.99, v, 0.01 * dr.square(g))
    s = dr.gather(mi.Float, lr, dr.arange(mi.UInt32, N) % 4) * dr.opaque(mi.Float, 0.5)
    x = x - m * (s / (dr.sqrt(v) + dr.opaque(mi.Float, 1e-8)))
    dr.eval(x, m, v)
    return x, m, v


def flat(x, m, v):
    lane = dr.arange(mi.UInt32, N)
    nm = dr.fma(0.9, memory_view(m), 0.1 * g)
    nv = dr.fma(0.99, memory_view(v), 0.01 * dr.square(g))
    s = dr.gather(mi.Float, lr, lane % 4) * dr.opaque(mi.Float, 0.5)
    x = x - nm * (s / (dr.sqrt(nv) + dr.opaque(mi.Float, 1e-8)))
    dr.scatter(m, nm, lane)
    dr.scatter(v, nv, lane)
    dr.eval(x, m, v)
    return x, m, v


def packet(x, m, v):
    lane = dr.arange(mi.UInt32, N // 4)
    grad = dr.gather(mi.Vector4f, g, lane)
    nm = dr.fma(0.9, dr.gather(mi.Vector4f, memory_view(m), lane), 0.1 * grad)
    nv = dr.fma(0.99, dr.gather(mi.Vector4f, memory_view(v), lane), 0.01 * dr.square(grad))
    s = mi.Vector4f(0.1, 0.05, 0.05, 0.05) * dr.opaque(mi.Float, 0.5)
    values = dr.gather(mi.Vector4f, x, lane) - nm * (s / (dr.sqrt(nv) + dr.opaque(mi.Float, 1e-8)))
    out = dr.empty(mi.Float, N)
    dr.scatter(m, nm, lane)
    dr.scatter(v, nv, lane)
    dr.scatter(out, values, lane)
    dr.eval(out, m, v)
    return out, m, v


KINDS = {"oop": oop, "flat": flat, "packet": packet}
for _ in range(2):
    for name in sys.argv[1:]:
        times = []
        for _ in range(6):
            dr.sync_thread()
            t0 = time.perf_counter()
            x, m, v = KINDS[name](x, m, v)
            dr.sync_thread()
            times.append(time.perf_counter() - t0)
        print(name, "%.1f ms" % (1e3 * np.median(times[2:])), float(x[N - 1]))
