"""Cost against scene content: one object in a small and in a large empty box, with and without
occupancy skipping. With skipping the cost should follow the occupied volume, not the box.

The object is a sphere of radius 0.4 (dense inside, empty outside) on a grid of fixed voxel size
filling a box of side ``size``; rays come from a camera-like sphere of radius 1.5 x size aimed at the
object; samples every half voxel (``step_size``), so rays through a larger box take more samples
unless empty space is skipped.
"""
import time

import drjit as dr
import mitsuba as mi
import numpy as np

from ..device import from_numpy
from ..field.activations import inverse_softplus
from ..field.spec import box_transform, field_dict
from ..render.march import prepare_rays, sample_count
from ..render.rays import render_rays

VOXEL = 0.02


def sphere_scene(size, occupancy):
    n = int(round(size / VOXEL)) + 1
    c = np.linspace(-size / 2, size / 2, n)
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    inside = np.sqrt(x ** 2 + y ** 2 + z ** 2) < 0.4
    density = np.where(inside, inverse_softplus(20.0), -30.0)[..., None]
    color = np.stack([0.4 * x, 0.4 * y, 0.4 * z], axis=-1)
    box = box_transform([-size / 2] * 3, [size / 2] * 3)
    empty = field_dict(np.full((2, 2, 2, 1), -30.0), np.zeros((2, 2, 2, 3)), box)
    integ = mi.load_dict({"type": "voldis", "samples": 4096, "step_size": VOXEL / 2,
                          "full": field_dict(density, color, box), "bg": empty}, optimize=False)
    if occupancy:
        integ.update_occupancy(int(round(size / VOXEL / 2)), 0.01)
    return integ


def rays(size, n, seed=0):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    o = 1.5 * size * v / np.linalg.norm(v, axis=1, keepdims=True)
    d = rng.uniform(-0.5, 0.5, (n, 3)) - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d), from_numpy(mi.Float, rng.uniform(0, 1, n))


def measure(size, occupancy, batch=8192, steps=3):
    """Per forward+backward step: seconds, evaluated samples per ray, loop iterations per ray."""
    integ = sphere_scene(size, occupancy)
    params = mi.traverse(integ)
    seconds, evaluated = [], []
    for k in range(steps + 1):
        o, d, u = rays(size, batch, k)
        dr.enable_grad(params["full.density"])
        params.update()
        t = time.perf_counter()
        out = render_rays(integ, o, d, u, layers=("full",))
        dr.backward(dr.mean(dr.squared_norm(out["full"][0])))
        dr.eval(dr.grad(params["full.density"]))
        dr.sync_thread()
        if k:  # the first step compiles the kernels
            seconds.append(time.perf_counter() - t)
            evaluated.append(float(dr.mean(out["evaluated"])[0]))
    plan = integ.plan(("full",))
    o, d, _ = rays(size, batch, 0)
    n, _ = sample_count(plan, prepare_rays(plan, o, d))
    return {"size": size, "occupancy": occupancy, "seconds": float(np.median(seconds)),
            "evaluated_per_ray": float(np.mean(evaluated)), "iterations_per_ray": float(dr.mean(mi.Float(n))[0]),
            "occupied_fraction": integ.occupancy.fraction if integ.occupancy is not None else 1.0}
