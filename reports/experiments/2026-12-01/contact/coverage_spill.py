"""Foreground coverage past the object: held-out views' coverage previews (above a half) outside the object's
mask, in two removal folders of the same scene.

    python coverage_spill.py DATA OLD_REMOVAL NEW_REMOVAL SCENE
"""
import glob
import os
import sys

import imageio.v3 as iio

import mi_voldis  # noqa: F401
from mi_voldis.data import load_dataset

data, old, new, scene = sys.argv[1:5]
ds = load_dataset(data, "transforms", 8)
for f in sorted(glob.glob(os.path.join(old, scene, "guided", "view*_coverage.png"))):
    v = int(os.path.basename(f)[4:7])
    counts = []
    for base in (old, new):
        c = iio.imread(os.path.join(base, scene, "guided", os.path.basename(f)))
        c = c if c.ndim == 2 else c[..., 0]
        counts.append(int(((c > 127) & ~ds.masks[v]).sum()))
    print(f"{scene} view {v}: coverage above a half outside the mask {counts[0]} -> {counts[1]} pixels "
          f"(mask {int(ds.masks[v].sum())})")
