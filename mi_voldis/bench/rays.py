"""Benchmark rays through the box [-1, 1]^3 (NumPy float32 arrays o, d (n, 3) and jitters u (n,)), the
same draws for the Dr.Jit march and the PyTorch reference.

* ``random``: origins on the sphere of radius 3 aimed at uniform points of [-0.8, 0.8]^3: every ray
  independent of its neighbours, the hardest case for caches.
* ``tiles``: coherent rays, 4 x 4 pixel tiles at random places of random views among 100 cameras on
  that sphere (256 x 256 pixels, 45 degrees, looking at the centre): what fitting draws with
  ``batch_tile=4``, and close to the rays of a rendered view.
"""
import numpy as np

from ..cameras import film_to_camera
from ..raybank import tile_pixels

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
        frames = _frames()
        t = 2 * np.tan(np.radians(FOV) / 2)
        u, v = (pixel % SIZE + rng.random(n)) / SIZE, (pixel // SIZE + rng.random(n)) / SIZE
        x, y = film_to_camera(u, v, t, t, 0.0, 0.0)
        o = -3.0 * frames[view, :, 2]
        d = np.einsum("nij,nj->ni", frames[view], np.stack([x, y, np.ones_like(x)], axis=-1))
    else:
        raise ValueError(f"ray kind must be one of {KINDS}, got '{kind}'")
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return o.astype(np.float32), d.astype(np.float32), rng.uniform(0, 1, n).astype(np.float32)


def _frames():
    """Camera-to-world rotations (Mitsuba frame: columns left, up, forward) of the benchmark's cameras,
    on the sphere of radius 3 looking at the centre, fixed for every seed: (VIEWS, 3, 3)."""
    forward = np.random.default_rng(12345).normal(size=(VIEWS, 3))
    forward /= -np.linalg.norm(forward, axis=1, keepdims=True)
    left = np.cross([0.0, 0.0, 1.0], forward)
    left /= np.linalg.norm(left, axis=1, keepdims=True)
    return np.stack([left, np.cross(forward, left), forward], axis=-1)
