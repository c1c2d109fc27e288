"""#46: the signed error of today's `guided` background against the true background on held-out views 0, 8 and
16: inside the mask grown by 1% and on the ring from 1% to 3% (the score's region), beside the photos' own error
on that ring (the object's shadow and bounce light), in 8-bit units; and the share of the MSE inside the 1% mask
that the mean error alone makes.
    python reports/experiments/2026-11-28/prior_seen/core_bias.py"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import FITS, guided_row, image, mask  # noqa: E402

from mi_voldis.metrics import dilate  # noqa: E402
from mi_voldis.synth import family  # noqa: E402

SCENES = ["01", "02", "04", "05", "06", "10", "11", "14", "15", "16", "17", "18", "19"]


def main():
    for s in SCENES:
        scene = f"family{s}"
        _, kind = family.scene(family.index(scene))
        core, ring, photo_ring, core_se, n_core = [], [], [], 0.0, 0
        for v in (0, 8, 16):
            truth = image(f"{FITS}/data/{scene}/backgrounds/view_{v:03d}.png")
            photo = image(f"{FITS}/data/{scene}/images/view_{v:03d}.png")
            ours = image(f"{guided_row(scene)}/view{v:03d}_bg.png")
            m = mask(scene, v)
            diag = np.hypot(*m.shape)
            inner = dilate(m, int(np.ceil(0.01 * diag)))
            band = dilate(m, int(np.ceil(0.03 * diag))) & ~inner
            core.append((ours - truth)[inner].mean(0))
            ring.append((ours - truth)[band].mean(0))
            photo_ring.append((photo - truth)[band].mean(0))
            core_se += ((ours - truth)[inner] ** 2).sum()
            n_core += inner.sum() * 3
        bias = np.mean(core, 0)
        share = (bias ** 2).mean() / (core_se / n_core)
        print(f"{scene} {kind}: core bias {np.round(bias * 255, 1)} ({share:.0%} of core mse) | ring bias "
              f"{np.round(np.mean(ring, 0) * 255, 1)} photo ring {np.round(np.mean(photo_ring, 0) * 255, 1)}")


if __name__ == "__main__":
    main()
