"""Whether Dr.Jit adds into a gradient in place: the RSS growth of a scatter_add into the gradient of a 50 M
float array while the parameter holds it, and after it lets go (reports/notes.md, 2026-11-27).

    python reports/experiments/2026-11-27/memory/scatter_in_place.py
"""
import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
def rss():
    return int(open("/proc/self/statm").read().split()[1]) * 4096 / 2**20
N = 50_000_000
for mode in ("plain", "disable_grad"):
    x = dr.zeros(mi.Float, N) + 1.0
    dr.eval(x)
    dr.enable_grad(x)
    idx = mi.UInt32(np.arange(0, N, 7).astype(np.uint32))
    loss = dr.sum(dr.gather(mi.Float, x, idx) ** 2)
    dr.backward(loss)
    g = dr.grad(x)
    dr.eval(g)
    if mode == "disable_grad":
        dr.disable_grad(x)
    del loss
    dr.flush_malloc_cache()
    r0 = rss()
    dr.scatter_add(g, mi.Float(1.0), dr.arange(mi.UInt32, N))
    dr.eval(g)
    print(mode, "RSS growth %.0f MiB (an array is %.0f)" % (rss() - r0, N * 4 / 2**20))
    del g, x, idx
    dr.flush_malloc_cache()
