"""Shared helpers: tiny scenes with analytic answers; killing a job after a checkpoint."""
import json
import os
import signal
import time

import drjit as dr
import mitsuba as mi
import numpy as np

import mi_voldis  # noqa: F401  (selects the variant, registers the plugins)
from mi_voldis.field.spec import box_transform, constant_field, field_dict  # noqa: F401 (re-exported)

UNIT_BOX = box_transform([-1, -1, -1], [1, 1, 1])


def random_field(seed, shape=(4, 4, 4), channels=3, to_world=UNIT_BOX, scale=1.0):
    rng = np.random.default_rng(seed)
    return field_dict(rng.normal(0, scale, shape + (1,)), rng.normal(0, scale, shape + (channels,)), to_world)


def integrator(full, bg, **props):
    return mi.load_dict({"type": "voldis", "full": full, "bg": bg, **props})


def axis_rays(n=16, z0=-3.0, spread=0.9, seed=0):
    """Rays along +z starting at z0, at random (x, y) inside [-spread, spread]^2."""
    rng = np.random.default_rng(seed)
    o = mi.Point3f(rng.uniform(-spread, spread, n), rng.uniform(-spread, spread, n), np.full(n, z0))
    d = mi.Vector3f(0.0, 0.0, 1.0)
    return o, dr.zeros(mi.Vector3f, n) + d, mi.Float(rng.uniform(0, 1, n))


def ortho_scene(integ_dict, size=8, spp=1, z0=-3.0, extent=1.0):
    """Scene looking down +z with an orthographic camera covering [-extent, extent]^2."""
    return mi.load_dict({
        "type": "scene", "integrator": integ_dict,
        "sensor": {"type": "orthographic",
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, z0], target=[0, 0, 0], up=[0, 1, 0])
                   @ mi.ScalarTransform4f().scale([extent, extent, 1]),
                   "film": {"type": "hdrfilm", "width": size, "height": size, "pixel_format": "rgb",
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp}}})


def numpy_layers(out):
    """{layer: (rgb (n,3), alpha (n,), depth (n,))} as NumPy arrays."""
    return {k: (np.array(v[0]).T, np.array(v[1]), np.array(v[2])) for k, v in out.items()
            if k not in ("evaluated", "fg_coverage")}


def check_gradient(params, key, loss, n_entries=4, eps=3e-3, rtol=0.02, seed=0):
    """Compare Dr.Jit's reverse-mode gradient of ``loss()`` w.r.t. ``params[key]`` with central finite
    differences on the entries of largest gradient and a few random ones. Returns the AD gradient."""
    dr.enable_grad(params[key])
    params.update()
    dr.backward(loss())
    grad = np.array(dr.grad(params[key])).ravel()
    base = np.array(params[key])
    dr.disable_grad(params[key])
    rng = np.random.default_rng(seed)
    entries = list(np.argsort(-np.abs(grad))[:n_entries]) + list(rng.integers(0, grad.size, 2))
    scale = np.abs(grad).max()
    with dr.suspend_grad():
        # a central difference of a float32 loss moves in steps of ulp(loss) / (2 eps): it cannot resolve less
        quantum = float(np.spacing(np.float32(np.abs(np.array(loss()).ravel()[0])))) / (2 * eps)
    assert scale > 0, f"{key}: gradient is identically zero"
    for j in entries:
        values = []
        for sign in (1, -1):
            b = base.copy().ravel()
            b[j] += sign * eps
            params[key] = mi.TensorXf(b.reshape(base.shape))
            params.update()
            with dr.suspend_grad():
                values.append(float(np.array(loss()).ravel()[0]))
        fd = (values[0] - values[1]) / (2 * eps)
        assert abs(fd - grad[j]) <= rtol * abs(fd) + 2e-3 * scale + 2 * quantum, f"{key}[{j}]: AD {grad[j]} vs FD {fd}"
    params[key] = mi.TensorXf(base)
    params.update()
    return grad


def kill_after_checkpoint(proc, checkpoint, step, timeout=120, phase=None):
    """SIGKILL ``proc`` once its ``checkpoint`` (.npz with a JSON ``__meta__``) has reached ``step`` (of
    ``phase``, when given)."""
    deadline = time.time() + timeout
    while time.time() < deadline and proc.poll() is None:
        if os.path.exists(checkpoint):
            try:
                with np.load(checkpoint) as f:
                    meta = json.loads(bytes(f["__meta__"]).decode())
                reached = meta["step"] if phase is None or meta["phase"] == phase else 0
            except (OSError, ValueError, KeyError):  # caught while being replaced: look again
                reached = 0
            if reached >= step:
                break
        time.sleep(0.02)
    assert proc.poll() is None, "the job finished before it could be killed"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
