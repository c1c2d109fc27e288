"""The light search's cosines on 0.5 M random points: NumPy's row sums against the columns of
`ObjectSurface.facing` (ms a call, and whether the bits agree).

    python facing_bench.py
"""
import time

import numpy as np

from mi_voldis.fit.shadow import ObjectSurface

rng = np.random.default_rng(0)
points, normals = rng.normal(size=(500_000, 3)), rng.normal(size=(500_000, 3))
normals /= np.linalg.norm(normals, axis=1, keepdims=True)
surface = ObjectSurface(points, normals, np.zeros(len(points)), 0.01)
light = np.array([3.0, -2.0, 5.0])


def rows():
    return np.sum((light - points) * normals, axis=1) / np.linalg.norm(light - points, axis=1)


for name, f in (("row sums", rows), ("facing (columns)", lambda: surface.facing(light))):
    f()
    t = time.perf_counter()
    for _ in range(20):
        out = f()
    print(f"{name}: {(time.perf_counter() - t) / 20 * 1e3:.1f} ms, same bits: {np.array_equal(out, rows())}")
