"""Side-by-side training-step time: degree 0, grey degree 1 (8 floats a vertex) and grey degree 1 with its
coefficients on a dense 128^3 view lattice. Run from a copy of the package with viewgrid.diff applied:
python steptime.py RES BATCH. A random cloud over the whole box, so every ray evaluates all 128 samples; the
rows alternate in one process and each prints its median of 6 steps."""
import os
import sys
import time

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")

from mi_voldis.field_state import new_field  # noqa: E402  (after the variant)
from mi_voldis.fieldspec import constant_field  # noqa: E402
from mi_voldis.plugins import radiance_field, voldis  # noqa: E402, F401  (registers the plugins)
from mi_voldis.render.rays import render_rays  # noqa: E402
from mi_voldis.scene import build_integrator  # noqa: E402

RES, BATCH = int(sys.argv[1]), int(sys.argv[2])
LO, HI = -np.ones(3), np.ones(3)


def make(kind, rng):
    """An integrator over a cloudy field of ``kind``: 'deg0', 'grey1' or 'view128'."""
    os.environ["MI_VOLDIS_VIEWGRID"] = "128" if kind == "view128" else "0"
    f = new_field(LO, HI, RES, 0 if kind == "deg0" else 1, 0.0, 0.5, grey=True, sh_gate=True)
    d = np.array(f.data)
    n = f.vertices * f.width
    d[:n] += rng.normal(0, 1, n).astype(np.float32)
    d[n:] = rng.normal(0, 0.3, len(d) - n).astype(np.float32)
    f.data = mi.Float(d)
    return build_integrator({"full": f.plugin(), "bg": constant_field(1e-12, (0, 0, 0))},
                            {"samples": 128, "step_size": 1.0 / RES})


def step(integ, seed):
    """One forward and backward pass of BATCH rays through the box; returns the samples evaluated."""
    r = np.random.default_rng(seed)
    o = r.uniform(-3, 3, (BATCH, 3)).astype(np.float32)
    o[:, 2] = -3
    t = r.uniform(-0.7, 0.7, (BATCH, 3)).astype(np.float32)
    t[:, 2] = 0
    d = t - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    packed = integ.fields["full"].packed
    dr.enable_grad(packed)
    out = render_rays(integ, mi.Point3f(o.T), mi.Vector3f(d.T), mi.Float(r.random(BATCH).astype(np.float32)),
                      ("full",))
    dr.backward(dr.sum(dr.sum(out["full"][0])))
    dr.eval(dr.grad(packed))
    dr.sync_thread()
    return float(dr.sum(out["evaluated"])[0])


rng = np.random.default_rng(0)
integs = {k: make(k, rng) for k in ("deg0", "grey1", "view128")}
times = {k: [] for k in integs}
for k in integs:  # warm-up: compile every kernel
    for s in range(2):
        step(integs[k], s)
for rnd in range(6):
    for k, integ in integs.items():
        t0 = time.perf_counter()
        samples = step(integ, 100 + rnd)
        times[k].append(time.perf_counter() - t0)
base = np.median(times["deg0"])
for k, v in times.items():
    print(f"{k:8s} median {np.median(v) * 1e3:8.1f} ms  ratio {np.median(v) / base:.2f}  samples {samples:.0f}")
