"""#46: OpenCV contrib FSR on every view of family scenes, its hole the object mask grown by 1, 2, 3 or 5% of
the diagonal, scored inside the mask grown by 1% (the colour prior's region) against the true background:
would a 2D prior that takes its sources beyond the object's contact shadow be closer?
    python reports/experiments/2026-11-28/prior_seen/source_gap_2d.py 01,02,04,05,06,17"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import FITS, image, mask  # noqa: E402

from mi_voldis.inpaint2d import inpainter  # noqa: E402
from mi_voldis.metrics import dilate  # noqa: E402

GAPS = (0.01, 0.02, 0.03, 0.05)


def main(scenes):
    fsr = inpainter("fsr")
    for s in scenes.split(","):
        scene = f"family{s}"
        row = []
        for gap in GAPS:
            errors = []
            for v in range(20):
                m = mask(scene, v)
                if not m.any():
                    continue
                truth = image(f"{FITS}/data/{scene}/backgrounds/view_{v:03d}.png")
                photo = image(f"{FITS}/data/{scene}/images/view_{v:03d}.png")
                diag = np.hypot(*m.shape)
                region = dilate(m, int(np.ceil(0.01 * diag)))
                filled = fsr(np.clip(photo, 0, 1), dilate(m, int(np.ceil(gap * diag))))
                errors.append(((filled - truth)[region] ** 2).mean())
            row.append(-10 * np.log10(np.mean(errors)))
        print(f"{scene}: " + " ".join(f"{g}:{p:.2f}" for g, p in zip(GAPS, row)), flush=True)


if __name__ == "__main__":
    main(sys.argv[1])
