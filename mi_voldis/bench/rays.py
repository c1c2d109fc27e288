"""Benchmark rays through the box [-1, 1]^3 (NumPy float32 arrays o, d (n, 3) and jitters u (n,)), the
same draws for the Dr.Jit march and the PyTorch reference.

* ``random``: origins on the sphere of radius 3 aimed at uniform points of [-0.8, 0.8]^3: every ray
  independent of its neighbours, the hardest case for caches.
* ``tiles``: coherent rays, 4 x 4 pixel tiles at random places of random views among 100 cameras on
  that sphere (256 x 256 pixels, 45 degrees, looking at the centre): what fitting draws with
  ``batch_tile=4``, and close to the rays of a rendered view.
"""
import numpy as np

from ..fit.raybank import tile_pixels

KINDS = ("random", "tiles")
VIEWS, SIZE, FOV, TILE = 100, 256, 45.0, 4


def bench_rays(kind, n, seed):
    rng = np.random.default_rng(seed)
    if kind == "random":
        v = rng.normal(size=(n, 3))
        o = 3.0 * v / np.linalg.norm(v, axis=1, keepdims=True)
        d = rng.uniform(-0.8, 0.8, (n, 3)) - o
    elif kind == "tiles":
        tile = TILE
        anchors = rng.integers(0, VIEWS * SIZE * SIZE, -(-n // (tile * tile)))
        view, pixel = np.divmod(tile_pixels(rng, anchors, tile, SIZE, SIZE)[:n], SIZE * SIZE)
        back, right, up = _cameras()
        scale = np.tan(np.radians(FOV) / 2)
        sx = (2 * (pixel % SIZE + rng.random(n)) / SIZE - 1) * scale
        sy = (2 * (pixel // SIZE + rng.random(n)) / SIZE - 1) * scale
        o = 3.0 * back[view]
        d = -back[view] + sx[:, None] * right[view] + sy[:, None] * up[view]
    else:
        raise ValueError(f"ray kind must be one of {KINDS}, got '{kind}'")
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return o.astype(np.float32), d.astype(np.float32), rng.uniform(0, 1, n).astype(np.float32)


def _cameras():
    """Unit vectors (back, right, up) of the benchmark's cameras, fixed for every seed."""
    back = np.random.default_rng(12345).normal(size=(VIEWS, 3))
    back /= np.linalg.norm(back, axis=1, keepdims=True)
    right = np.cross([0.0, 0.0, 1.0], -back)
    right /= np.linalg.norm(right, axis=1, keepdims=True)
    return back, right, np.cross(-back, right)
