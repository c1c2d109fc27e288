"""Is a fit's held-out error blur, misalignment or exposure? Per previewed held-out view of RUN: PSNR of
the render against the photograph, after the best sub-pixel shift (phase correlation), against the
photograph blurred by a Gaussian of sigma 1 px, and the mean colour offset; and the contracted space's
linear cube against the camera distances and the sparse points.

    python reports/experiments/2026-11-27/gpu/garden_blur.py ../shared/data/garden RUN
"""
import sys

import cv2
import imageio.v3 as iio
import numpy as np

from mi_voldis.data import load_dataset
from mi_voldis.data.scene_box import contracted_box, look_at_point
from mi_voldis.io.images import display_to_uint8
from mi_voldis.metrics import psnr


def main(data, run):
    ds = load_dataset(data)
    for v in ds.test[:3]:
        render = iio.imread(f"{run}/previews/view{v:03d}_full.png")[..., :3].astype(np.float32) / 255
        photo = display_to_uint8(ds.images[v]).astype(np.float32) / 255
        grey = [cv2.cvtColor(x, cv2.COLOR_RGB2GRAY).astype(np.float64) for x in (photo, render)]
        (dx, dy), _ = cv2.phaseCorrelate(*grey)
        shifted = cv2.warpAffine(render, np.float32([[1, 0, -dx], [0, 1, -dy]]), render.shape[1::-1],
                                 flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        inner = (slice(8, -8), slice(8, -8))
        print(f"view {v}: {psnr(render, photo):.2f} dB; shift ({dx:.2f}, {dy:.2f}) px -> "
              f"{psnr(shifted[inner], photo[inner]):.2f}; photo blurred (sigma 1 px) "
              f"{psnr(render, cv2.GaussianBlur(photo, (0, 0), 1.0)):.2f}; mean offset "
              f"{(render - photo).reshape(-1, 3).mean(0).round(3).tolist()}")
    centre = look_at_point(ds.cameras)
    cams = np.linalg.norm(np.array([np.asarray(c.to_world)[:3, 3] for c in ds.cameras]) - centre, axis=1)
    box = contracted_box(ds.cameras, False)
    print(f"camera distance from the look-at point: min {cams.min():.2f}, median {np.median(cams):.2f}, max "
          f"{cams.max():.2f}; the linear cube's half-size {box.to_world[0, 0]:.2f}")
    if ds.points is not None:
        d = np.linalg.norm(ds.points - centre, axis=1)
        print("sparse points' distance quantiles 10/25/50/75:", np.percentile(d, [10, 25, 50, 75]).round(2).tolist())


if __name__ == "__main__":
    main(*sys.argv[1:])
