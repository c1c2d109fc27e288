"""Side-by-side training-step time: degree 0, grey degree 1 (8 wide), grey degree 1 on a dense view grid."""
import os, sys, time
import numpy as np
import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
import drjit as dr
from mi_voldis.field_state import new_field
from mi_voldis.fieldspec import constant_field
from mi_voldis.scene import build_integrator
from mi_voldis.render.rays import render_rays
from mi_voldis.plugins import radiance_field, voldis  # noqa

RES, BATCH = int(sys.argv[1]), int(sys.argv[2])
lo, hi = -np.ones(3), np.ones(3)
rng = np.random.default_rng(0)

def make(kind):
    os.environ["MI_VOLDIS_VIEWGRID"] = "128" if kind == "view128" else "0"
    f = new_field(lo, hi, RES, 0 if kind == "deg0" else 1, 0.0, 0.5, grey=True, sh_gate=True)
    d = np.array(f.data); n = f.vertices * f.width
    d[:n] += rng.normal(0, 1, n).astype(np.float32)  # a cloudy field: every sample evaluated
    d[n:] = rng.normal(0, 0.3, len(d) - n).astype(np.float32)
    f.data = mi.Float(d)
    integ = build_integrator({"full": f.plugin(), "bg": constant_field(1e-12, (0, 0, 0))},
                             {"samples": 128, "step_size": 1.0 / RES})
    return integ

def step(integ, seed):
    r = np.random.default_rng(seed)
    o = r.uniform(-3, 3, (BATCH, 3)).astype(np.float32); o[:, 2] = -3
    t = r.uniform(-0.7, 0.7, (BATCH, 3)).astype(np.float32); t[:, 2] = 0
    d = t - o; d /= np.linalg.norm(d, axis=1, keepdims=True)
    field = integ.fields["full"]
    p = field.packed; dr.enable_grad(p)
    out = render_rays(integ, mi.Point3f(o.T), mi.Vector3f(d.T), mi.Float(r.random(BATCH).astype(np.float32)), ("full",))
    loss = dr.sum(dr.sum(out["full"][0]))
    dr.backward(loss)
    g = dr.grad(p); dr.eval(g); dr.sync_thread()
    return float(dr.sum(out["evaluated"])[0])

integs = {k: make(k) for k in ("deg0", "grey1", "view128")}
times = {k: [] for k in integs}
for k in integs:
    for s in range(2):
        step(integs[k], s)
for rnd in range(6):
    for k, integ in integs.items():
        t = time.perf_counter(); n = step(integ, 100 + rnd); times[k].append(time.perf_counter() - t)
base = np.median(times["deg0"])
for k, v in times.items():
    print(f"{k:8s} median {np.median(v)*1e3:8.1f} ms  ratio {np.median(v)/base:.2f}  samples {n:.0f}")
