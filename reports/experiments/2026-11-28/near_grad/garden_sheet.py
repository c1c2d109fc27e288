"""Contact sheet of garden's held-out views: photo, then each run's full-field render (from
`python scripts/render.py RUN/scene.xml --out DIR --cameras ../shared/data/garden --split test --layer full`).

    python reports/experiments/2026-11-28/near_grad/garden_sheet.py OUT.png FRAMES DIR [DIR ...]

FRAMES: comma-separated image names without extension (frame_00053,...); one row each.
"""
import os
import sys

import cv2
import numpy as np

GARDEN = os.path.join(os.path.dirname(__file__), *[".."] * 5, "shared", "data", "garden", "images")


def main(out, frames, *dirs):
    if os.path.exists(out):
        sys.exit(f"{out}: exists; not overwritten")
    rows = []
    for name in frames.split(","):
        renders = [cv2.imread(os.path.join(d, f"{name}_full.png")) for d in dirs]
        if any(r is None for r in renders):
            sys.exit(f"{name}: a render is missing in {dirs}")
        h, w = renders[0].shape[:2]
        photo = cv2.resize(cv2.imread(os.path.join(GARDEN, f"{name}.jpg")), (w, h), interpolation=cv2.INTER_AREA)
        rows.append(np.concatenate([photo] + renders, axis=1))
    sheet = np.concatenate(rows, axis=0)
    cv2.imwrite(out, cv2.resize(sheet, (sheet.shape[1] // 2, sheet.shape[0] // 2), interpolation=cv2.INTER_AREA))


if __name__ == "__main__":
    main(*sys.argv[1:])
