"""Shared by this folder's scripts: the removal family's data and rows as the 2026-11-28 runs left them."""
import os

import imageio.v3 as iio
import numpy as np

FITS = "/work/runs/fam"  # bench.py --family --work: data/familyNN, removal/familyNN/guided
TODAY = "/work/runs/trial/v0"  # screen.sh under hull_fill_vertical=0 (today's default), where the bench has no row


def image(path):
    """An 8-bit PNG as float RGB in [0, 1]."""
    return iio.imread(path)[..., :3].astype(np.float32) / 255


def mask(scene, view):
    m = iio.imread(f"{FITS}/data/{scene}/masks/view_{view:03d}.png")
    return (m[..., 0] if m.ndim == 3 else m) > 127


def guided_row(scene):
    """The folder of today's `guided` background for ``scene`` (PNG previews and metrics.json)."""
    bench = f"{FITS}/removal/{scene}/guided"
    return bench if os.path.exists(f"{bench}/metrics.json") else f"{TODAY}/{scene}"
