"""How many vertices smaller bricks would store around a fitted field's surfaces: a proxy, before any fit.

    python reports/experiments/2026-12-06d/brick_proxy.py RUN/full_grid.npz > OUT.txt

Reads a fitted brick grid (its bricks of B vertices), marks the vertices whose raw density passes a threshold t
(a stand-in for fitting's carve, which keeps bricks where training rays end), and counts, for bricks of 8, 4
and 2 vertices, the bricks holding a marked vertex, grown by one brick in all 26 directions as fitting grows its
carve (``dilate_bricks``), and the vertices they store. Thresholds from fog (-5) to opaque (+2).
"""
import sys

import numpy as np

z = np.load(sys.argv[1])
table, raw, brick = z["table"], z["data"][:, 0], int(z["brick"])
counts = table.shape
dense = np.full(tuple(c * brick for c in counts), -20.0, np.float32)  # unallocated: the empty brick's density
blocks = raw.reshape(-1, brick, brick, brick)  # the file holds slots 1..n (x fastest within a brick)
for (a, b, c) in zip(*np.nonzero(table)):
    dense[a * brick:(a + 1) * brick, b * brick:(b + 1) * brick, c * brick:(c + 1) * brick] = blocks[table[a, b, c] - 1]
print(f"{sys.argv[1]}: {int((table > 0).sum())} bricks of {brick}, {int((table > 0).sum()) * brick ** 3 / 1e6:.2f} M "
      f"stored vertices; raw density quantiles 10/50/90/99%: {np.round(np.quantile(raw, [0.1, 0.5, 0.9, 0.99]), 2)}")


def grown(keep):
    """``keep`` grown by one cell in all 26 directions."""
    padded, out = np.pad(keep, 1), np.zeros_like(keep)
    n = keep.shape
    for dz in range(3):
        for dy in range(3):
            for dx in range(3):
                out |= padded[dz:dz + n[0], dy:dy + n[1], dx:dx + n[2]]
    return out


for t in (-5, -2, 0, 2):
    marked = dense > t
    stored = {}
    for b in (8, 4, 2):
        s = [n // b for n in marked.shape]
        keep = marked[:s[0] * b, :s[1] * b, :s[2] * b].reshape(s[0], b, s[1], b, s[2], b).any(axis=(1, 3, 5))
        stored[b] = grown(keep).sum() * b ** 3
    print(f"t = {t:+d}: stored vertices, bricks of 8 / 4 / 2: {stored[8] / 1e6:.2f} / {stored[4] / 1e6:.2f} / "
          f"{stored[2] / 1e6:.2f} M (4 over 8: {stored[4] / stored[8]:.2f})")
