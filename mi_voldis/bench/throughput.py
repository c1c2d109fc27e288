"""Ray-marcher throughput: samples per second of the voldis march, forward and forward+backward+Adam.

Rays (:mod:`.rays`: ``random`` or fitting's ``tiles``) cross the box [-1, 1]^3 holding a random
density+colour grid. A "sample" is one point on a ray where the fields are evaluated (rays x samples
per ray). The training step is fitting's: Adam on the packed grids (:class:`PackedParameters`).
"""
import time

import drjit as dr
import mitsuba as mi
import numpy as np

from ..device import from_numpy
from ..field.spec import box_transform, brick_field_dict, field_dict
from ..optim.adam import Adam
from ..optim.parameters import PackedParameters
from ..render import march
from ..render.rays import render_rays
from .rays import bench_rays


def device_rays(kind, n, seed):
    o, d, u = bench_rays(kind, n, seed)
    return from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d), from_numpy(mi.Float, u)


VIEW_RESOLUTION = 64  # the view lattice of representation "view": sh_view_resolution's default


def make_integrator(resolution, samples, channels=3, seed=0, representation="bricks"):
    """Two random fields (raw density normal(-1, 1), colour normal(0, 1)) of R^3 vertices over [-1, 1]^3,
    dense, in bricks (every brick allocated: the same field) or, for "view", in bricks with grey
    view dependence on a VIEW_RESOLUTION^3 view lattice (gloss coefficients normal(0, 0.3))."""
    rng = np.random.default_rng(seed)
    box = box_transform([-1, -1, -1], [1, 1, 1])
    shape = (resolution,) * 3
    make = field_dict if representation == "dense" else brick_field_dict
    specs = {role: make(rng.normal(-1, 1, shape + (1,)), rng.normal(0, 1, shape + (channels,)), box)
             for role in ("full", "bg")}
    if representation == "view":
        for spec in specs.values():
            spec["view"] = mi.TensorXf(rng.normal(0, 0.3, (VIEW_RESOLUTION,) * 3 + (3,)).astype(np.float32))
    return mi.load_dict({"type": "voldis", "samples": samples, **specs}, optimize=False)


def trainer(resolution, samples, channels=3, fields=("full",), rays="random", representation="bricks"):
    """(integrator, step function): ``step(o, d, u)`` runs one training step as fitting does (forward,
    backward, Adam on the packed grids) on the rays ``o``, ``d`` with jitters ``u`` (:func:`device_rays`)
    and returns the samples evaluated."""
    integ = make_integrator(resolution, samples, channels, representation=representation)
    params = PackedParameters({role: integ.fields[role] for role in fields})
    adam = Adam({key: 1e-2 for key in params})
    target = mi.Color3f(0.5, 0.4, 0.3)

    def step(o, d, u):
        for key in params:
            dr.enable_grad(params[key])
        params.update()
        out = render_rays(integ, o, d, u, layers=fields)
        loss = sum(dr.mean(dr.square(out[lay][0] - target)) for lay in fields)
        dr.backward(loss)
        adam.step(params, {key: dr.grad(params[key]) for key in params})
        params.update()
        dr.eval([params[key] for key in params])  # the update itself (the container is not traversed)
        return float(dr.sum(out["evaluated"])[0])
    return integ, step


def step_functions(resolution, samples, batch, channels=3, fields=("full",), rays="random", representation="bricks"):
    """{"forward": f, "train": f}: ``f(seed)`` runs one forward (no gradients) or one training step
    (forward + backward + Adam) on fresh ``rays``, waits for it, and returns the samples evaluated."""
    integ, train_step = trainer(resolution, samples, channels, fields, rays, representation)
    layers = tuple(dict.fromkeys(fields))

    def forward(seed):
        o, d, u = device_rays(rays, batch, seed)
        with dr.suspend_grad():
            out = render_rays(integ, o, d, u, layers=layers)
            dr.eval(out)
        evaluated = float(dr.sum(out["evaluated"])[0])
        dr.sync_thread()
        return evaluated

    def train(seed):
        evaluated = train_step(*device_rays(rays, batch, seed))
        dr.sync_thread()
        return evaluated
    return {"forward": forward, "train": train}


def interleaved(impls, steps, warmup, rounds=2):
    """Time several implementations in alternating blocks (a block of each, ``rounds`` times), so that
    the load of a shared machine falls on all of them alike. Each block starts with untimed steps
    (``warmup[name]`` in the first round, one later): Dr.Jit runs slower right after PyTorch steps
    than alone (reports/notes.md), so blocks, not single steps, alternate.
    ``impls``: {name: {phase: f(seed) -> samples}}; ``steps``: timed steps of each, over all rounds.
    Returns {name: {phase: {"seconds": median seconds per step, "msps": million samples per second
    at that median}}}."""
    per_round = -(-steps // rounds)
    result = {name: {} for name in impls}
    for phase in ("forward", "train"):
        seconds = {name: [] for name in impls}
        samples = {name: [] for name in impls}
        seed = 0
        for r in range(rounds):
            for name, fns in impls.items():
                for _ in range(warmup[name] if r == 0 else 1):
                    fns[phase](seed)
                    seed += 1
                for _ in range(per_round):
                    t = time.perf_counter()
                    samples[name].append(fns[phase](seed))
                    seconds[name].append(time.perf_counter() - t)
                    seed += 1
        for name in impls:
            median = float(np.median(seconds[name]))
            result[name][phase] = {"seconds": median, "msps": float(np.mean(samples[name])) / median / 1e6}
    return result


def measure(resolution, samples, batch, channels=3, fields=("full",), steps=5, warmup=2, rays="random"):
    """Median seconds per forward and per training step, and million samples per second of each."""
    fns = step_functions(resolution, samples, batch, channels, fields, rays)
    return interleaved({"voldis": fns}, steps, {"voldis": warmup}, rounds=1)["voldis"]


def march_kernel_ms(kernels, label):
    """Milliseconds of the kernel history's ``kernels`` whose code holds the loop labelled ``label``."""
    def code(h):
        ir = h.get("ir")
        return ir.getvalue() if hasattr(ir, "getvalue") else str(ir or "")
    return sum(h["execution_time"] for h in kernels if label in code(h))


def step_profile(resolution=128, samples=128, batch=16384, steps=5, warmup=3, rays="random", record=True):
    """Where a training step's time goes, from Dr.Jit's kernel history (median ms over ``steps``):
    the primal march kernel, the adjoint march kernel (the kernels holding the march's loops), every
    other kernel (packing, gradients, Adam), the step's wall-clock time, ``kernel_share``: the kernels'
    time over the step's (the rest is the host's: tracing, launching, waiting), and ``compiled``: kernels
    built (not found in a cache) during the profiled steps, which should be 0. ``record=False``: the
    adjoint reads the grid again instead of the primal's record (:class:`march.Record`). Each step's rays
    are on the device before it starts (fitting draws them from its ray bank there), so NumPy's ray
    generation is not charged to the step."""
    _, train_step = trainer(resolution, samples, rays=rays)
    limit = march.RECORD_BYTES
    march.RECORD_BYTES = limit if record else 0
    flag = dr.flag(dr.JitFlag.KernelHistory)
    rows = []
    try:
        for k in range(warmup):
            train_step(*device_rays(rays, batch, k))
        dr.sync_thread()
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        for k in range(steps):
            o, d, u = device_rays(rays, batch, warmup + k)
            dr.eval(o, d, u)
            dr.sync_thread()
            dr.kernel_history()  # drop what came before
            t = time.perf_counter()
            evaluated = train_step(o, d, u)
            dr.sync_thread()
            wall = 1e3 * (time.perf_counter() - t)
            kernels = [h for h in dr.kernel_history() if "execution_time" in h]
            total = sum(h["execution_time"] for h in kernels)
            primal, adjoint = (march_kernel_ms(kernels, label) for label in ("voldis primal", "voldis adjoint"))
            rows.append({"primal_ms": primal, "adjoint_ms": adjoint, "other_kernels_ms": total - primal - adjoint,
                         "step_ms": wall, "msps": evaluated / wall / 1e3, "kernel_share": total / wall,
                         "compiled": sum(not h.get("cache_hit", True) for h in kernels)})
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, flag)
        march.RECORD_BYTES = limit
    out = {key: float(np.median([r[key] for r in rows])) for key in rows[0]}
    out["compiled"] = sum(r["compiled"] for r in rows)
    return out
