"""The default fit with each training batch's pixels in memory order (sorted flat indices: view, then row,
then column) instead of the order they were drawn in. The batch is the same set of rays with the same jitters
drawn, so a step's loss is the same sum in another order; only the order the march's SIMD lanes and threads
take the rays in changes (neighbouring lanes then march neighbouring rays of one view: similar lengths, the
same cache lines).

    python reports/experiments/2026-12-07/sorted_trial.py DATASET --out RUN [train.py's options]
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.getcwd())
from mi_voldis import raybank  # noqa: E402
from voldis_cli.train import entry  # noqa: E402

drawn = raybank.RayBank.batch


def batch(self, rng, n, pool=None, tile=1):
    if tile > 1:
        return drawn(self, rng, n, pool, tile)
    pool = self.keep if pool is None else pool
    idx = rng.integers(0, self.pixels, n) if pool is None else pool[rng.integers(0, len(pool), n)]
    return self.rays(np.sort(idx).astype(np.uint32), rng.random((n, 2), np.float32))


raybank.RayBank.batch = batch
entry()
