"""How far each held-out camera of a capture lies from its nearest training camera, in the rig's median spacing
between consecutive cameras (every k-th view held out, as train.py's --holdout).

usage: python camera_gaps.py DATASET [HOLDOUT]   (run from the checkout, with the package importable)
"""
import sys

import numpy as np

from mi_voldis.data import load_dataset

ds = load_dataset(sys.argv[1])
k = int(sys.argv[2]) if len(sys.argv) > 2 else 8
centres = np.array([np.asarray(cam.to_world)[:3, 3] for cam in ds.cameras])
test = [v for v in range(len(centres)) if v % k == 0]
train = [v for v in range(len(centres)) if v % k]
spacing = np.median(np.linalg.norm(np.diff(centres, axis=0), axis=1))
for v in test:
    d = np.linalg.norm(centres[train] - centres[v], axis=1)
    print(f"view {v}: nearest training view {train[int(d.argmin())]}, {d.min() / spacing:.2f} spacings away")
