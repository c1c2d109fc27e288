"""Contact sheet of held-out views: the photo, then each run's full-field preview (RUN/previews/viewNNN_full.png).

    python reports/experiments/2026-11-28/grey_sh/preview_sheet.py OUT.png DATASET VIEWS RUN [RUN ...]

VIEWS: comma-separated held-out view numbers that every run previewed (0,8,16); one row each, halved.
"""
import os
import sys

import cv2
import numpy as np


def main(out, dataset, views, *runs):
    if os.path.exists(out):
        sys.exit(f"{out}: exists; not overwritten")
    import mi_voldis  # noqa: F401
    from mi_voldis.data import load_dataset
    ds = load_dataset(dataset)
    rows = []
    for v in (int(x) for x in views.split(",")):
        photo = cv2.cvtColor((np.clip(ds.images[v], 0, 1) * 255 + 0.5).astype(np.uint8), cv2.COLOR_RGB2BGR)
        tiles = [photo] + [cv2.imread(os.path.join(r, "previews", f"view{v:03d}_full.png")) for r in runs]
        rows.append(np.concatenate([cv2.resize(t, (t.shape[1] // 2, t.shape[0] // 2), interpolation=cv2.INTER_AREA)
                                    for t in tiles], 1))
    cv2.imwrite(out, np.concatenate(rows, 0))


if __name__ == "__main__":
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    main(*sys.argv[1:])
