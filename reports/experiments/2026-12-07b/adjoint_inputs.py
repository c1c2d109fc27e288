"""Training steps of a fitted run's full field (fitting's rules, cells of 4 voxels, the distortion loss, Adam at a
negligible rate), three ways side by side in interleaved blocks in one process:
- ``old``: render_rays as at 9a8eebd: the primal's sums were not evaluated with its outputs, so the adjoint's
  kernel marched the primal loop again to get them;
- ``sums evaluated``: the sums evaluated in the primal's kernel, the rays replayed as marched;
- ``sums evaluated, sorted adjoint``: the package's default since: the adjoint replays the rays sorted by the
  primal's iterations per ray.
Prints each variant's gradient against ``old`` (one batch) and its median seconds a step.

    ROUNDS=5 python reports/experiments/2026-12-07b/adjoint_inputs.py RUN
"""
import os
import sys
import time

import drjit as dr
import mitsuba as mi
import numpy as np

sys.path.insert(0, os.getcwd())
mi.set_variant("llvm_ad_rgb")
from mi_voldis import load_run  # noqa: E402
from mi_voldis.optim.adam import Adam  # noqa: E402
from mi_voldis.optim.parameters import PackedParameters  # noqa: E402
from mi_voldis.raybank import RayBank  # noqa: E402
from mi_voldis.render import layers as layer_io  # noqa: E402
from mi_voldis.render import march  # noqa: E402
from mi_voldis.render import rays as rays_module  # noqa: E402
from mi_voldis.render.rays import render_rays  # noqa: E402

BATCH, BLOCK = 8192, 6
SORTER, NEW_EVAL = march.adjoint_order, rays_module._RenderRays.eval


def old_eval(self, tracked, plan, o, d, u, t_min, t_max):
    """``_RenderRays.eval`` as at 9a8eebd: only the outputs evaluated, no adjoint order."""
    rays = march.prepare_rays(plan, o, d, t_min, t_max)
    self.fwd = march.forward(plan, rays, u, True, keep_record=bool(tracked))
    self.sums = layer_io.raw_sums(plan, self.fwd.acc)
    out = layer_io.finalize(self.sums)
    out.update(self.fwd.stats)
    out.pop("iterations")
    if plan.distortion_chains:
        out["distortion"] = {layer: march.distortion_value(self.fwd.acc[march.dist_name(c)])
                             for layer, c in plan.distortion_chains.items()}
    dr.eval(out)
    return out


VARIANTS = {"old": (old_eval, False), "sums evaluated": (NEW_EVAL, False),
            "sums evaluated, sorted adjoint": (NEW_EVAL, True)}


def use(name):
    evaluate, ordered = VARIANTS[name]
    rays_module._RenderRays.eval = evaluate
    march.adjoint_order = SORTER if ordered else (lambda iterations: None)


if len(sys.argv) < 2:
    sys.exit("adjoint_inputs.py: give a fitted run's folder")
run = load_run(sys.argv[1])
ds = run.dataset
bank = RayBank(ds, ds.train)
resolution = max(run.integrator().fields["full"].shape)
integ = run.integrator(occupancy_resolution=int(np.ceil((resolution - 1) / 4)), stop_transmittance=1e-4)
params = PackedParameters({"full": integ.fields["full"]})
adam = Adam({key: 1e-12 for key in params})
rng = np.random.default_rng(0)
batches = [bank.batch(rng, BATCH) for _ in range(BLOCK + 1)]


def step(batch, gradient_only=False):
    o, d, color, *_ = batch
    for key in params:
        dr.disable_grad(params[key])
        dr.enable_grad(params[key])
    params.update()
    out = render_rays(integ, o, d, dr.full(mi.Float, 0.5, BATCH), layers=("full",), distortion=("full",))
    loss = dr.mean(dr.square(out["full"][0] - color)) + 1e-2 * dr.mean(out["distortion"]["full"])
    dr.backward(loss)
    grads = {key: dr.grad(params[key]) for key in params}
    if gradient_only:
        return np.array(grads["full.packed"])
    adam.step(params, grads)
    params.update()
    dr.eval([params[key] for key in params])
    return float(dr.sum(out["evaluated"])[0])


gradients = {}
for name in VARIANTS:
    use(name)
    gradients[name] = step(batches[0], gradient_only=True)
for name, g in gradients.items():
    ref = gradients["old"]
    print(f"{name}: gradient against old, max abs difference {np.abs(g - ref).max():.3g} "
          f"of max {np.abs(ref).max():.3g}")
times = {name: [] for name in VARIANTS}
for _ in range(int(os.environ.get("ROUNDS", 4))):
    for name in VARIANTS:
        use(name)
        step(batches[0])  # warm-up
        for batch in batches[1:]:
            t0 = time.perf_counter()
            step(batch)
            times[name].append(time.perf_counter() - t0)
base = np.median(times["old"])
for name, t in times.items():
    print(f"{name}: {1e3 * np.median(t):.1f} ms a step ({np.median(t) / base:.3f} x old)")
