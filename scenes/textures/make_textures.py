"""Generate the bundled scenes' textures (deterministic): soft-edged tiles and stripes.

    python scenes/textures/make_textures.py

Soft edges keep the patterns non-trivial to inpaint while staying representable by voxel grids of a
few hundred cells (a hard checkerboard puts sub-voxel edges everywhere).
"""
import os

import imageio.v3 as iio
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def soft_tiles(size, tiles, c0, c1, softness=0.18, seed=0):
    """Checkerboard of ``tiles`` x ``tiles`` with smoothed edges and a faint low-frequency tint."""
    u = (np.arange(size) + 0.5) / size * tiles
    fu = np.abs(((u % 1.0) - 0.5) * 2)  # 1 at tile edges, 0 at centres
    su = np.sign(np.sin(np.pi * u))
    wu = smoothstep((1 - fu) / softness)  # 0 at the edge, 1 inside
    check = 0.5 + 0.5 * np.outer(su * wu, su * wu)
    rng = np.random.default_rng(seed)
    k = rng.normal(size=(4, 4))
    y, x = np.mgrid[0:size, 0:size] / size
    tint = sum(k[i, j] * np.cos(np.pi * (i * x + j * y)) for i in range(4) for j in range(4)) * 0.04
    img = (1 - check)[..., None] * np.asarray(c0) + check[..., None] * np.asarray(c1) + tint[..., None]
    return np.clip(img, 0, 1)


def soft_stripes(size, stripes, c0, c1, softness=0.25):
    u = (np.arange(size) + 0.5) / size * stripes
    s = 0.5 + 0.5 * np.sin(2 * np.pi * u) / max(softness * 4, 1e-3)
    s = smoothstep(s)
    row = (1 - s)[:, None] * np.asarray(c0) + s[:, None] * np.asarray(c1)
    return np.repeat(row[None], size // 4, axis=0)


def write(name, img):
    iio.imwrite(os.path.join(HERE, name), np.round(np.clip(img, 0, 1) * 255).astype(np.uint8))


if __name__ == "__main__":
    write("floor_tiles.png", soft_tiles(512, 6, (0.72, 0.68, 0.60), (0.28, 0.33, 0.38), seed=1))
    write("panel_stripes.png", soft_stripes(512, 8, (0.85, 0.55, 0.20), (0.20, 0.55, 0.45)))
    write("room_floor.png", soft_tiles(512, 5, (0.68, 0.60, 0.48), (0.32, 0.24, 0.20), seed=2))
    write("room_wall.png", soft_stripes(512, 7, (0.55, 0.70, 0.80), (0.82, 0.80, 0.74)))
