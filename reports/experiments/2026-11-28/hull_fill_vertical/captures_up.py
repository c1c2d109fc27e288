"""The world's up (mi_voldis.cameras.world_up) of the captures in ../shared/data, with the normalised
eigenvalues of sum x x^T of their training cameras' +x axes:
    python reports/experiments/2026-11-28/hull_fill_vertical/captures_up.py [DATA]"""
import os
import sys

import numpy as np

import mi_voldis  # noqa: F401
from mi_voldis.cameras import world_up
from mi_voldis.data import load_dataset

data = sys.argv[1] if len(sys.argv) > 1 else "../shared/data"
for capture in ("statue", "garden", "fern", "horns"):
    ds = load_dataset(os.path.join(data, capture))
    cams = [ds.cameras[i] for i in ds.train]
    x = np.stack([c.to_world[:3, 0] for c in cams])
    ev = np.linalg.eigvalsh(x.T @ x)
    print(capture, "up", np.round(world_up(cams), 3), "eigenvalues", np.round(ev / ev[-1], 3))
