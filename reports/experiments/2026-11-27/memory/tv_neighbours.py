"""TV passes on a fitted field's brick layout: the neighbour tables stored and read, or computed in the kernel
from the brick table (reports/notes.md, 2026-11-27).

    python reports/experiments/2026-11-27/memory/tv_neighbours.py RUN   (RUN: a finished fit's folder)
"""
import sys
import time

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
from mi_voldis import field_state  # noqa: E402
from mi_voldis.bricks import Layout  # noqa: E402
from mi_voldis.regularizers import tv_gradient  # noqa: E402

z = np.load(sys.argv[1] + '/full_grid.npz')
layout = Layout(tuple(z['vertices']), int(z['brick']), z['table'])
state = field_state.FieldState(layout, mi.Float(np.zeros((layout.slots*512*4), np.float32)), 4, np.eye(4))
vals = mi.Float(np.concatenate([np.zeros(512*4, np.float32), z['data'].ravel()]))
dr.eval(vals)

def packets_direct(values, width, neighbours):
    n, packets = dr.width(values), width // 4
    vertex = dr.arange(mi.UInt32, n // width)
    out = dr.zeros(mi.Float, n)
    for k in range(packets):
        centre = dr.gather(mi.Vector4f, values, vertex * packets + k)
        total = mi.Vector4f(0.0)
        for nb in neighbours:
            total += 2.0 * (centre - dr.gather(mi.Vector4f, values, nb * packets + k))
        dr.scatter(out, total * (1.0 / n), vertex * packets + k)
    return out

def t(f, k=5):
    ts = []
    for _ in range(k):
        t0 = time.perf_counter()
        r = f()
        dr.eval(r)
        dr.sync_thread()
        ts.append(time.perf_counter() - t0)
    return np.median(ts), r
stored = field_state.neighbour_vertices(state)
a, ra = t(lambda: tv_gradient(vals, 4, stored))
b, rb = t(lambda: packets_direct(vals, 4, stored))
c, rc = t(lambda: packets_direct(vals, 4, field_state.neighbour_vertices(state, evaluate=False)))
d, _ = t(lambda: field_state.neighbour_vertices(state))
print("stored tables via gather %.3f, direct %.3f, computed in-kernel %.3f; building tables %.3f" % (a, b, c, d))
print(np.abs(np.array(ra) - np.array(rc)).max(), np.abs(np.array(ra) - np.array(rb)).max())
