"""A contact sheet of runs' held-out previews: a row per (run, view), columns the photo, then the run's
full field, its depth, background and foreground previews (each run's `previews/` folder).

    python previews.py OUT.png VIEWS RUN [RUN ...]      # VIEWS: comma-separated held-out views, e.g. 0,16
"""
import os
import sys

import numpy as np
from PIL import Image

if len(sys.argv) < 4:
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
out, views, runs = sys.argv[1], [int(v) for v in sys.argv[2].split(",")], sys.argv[3:]
if os.path.lexists(out):
    raise SystemExit(f"previews.py: {out} exists; give a new file")
size = (256, 192)


def tile(path):
    if not os.path.isfile(path):
        raise SystemExit(f"previews.py: {path}: no such preview")
    return np.array(Image.open(path).convert("RGB").resize(size, Image.NEAREST))


rows = []
for run in runs:
    data = os.path.join(os.path.dirname(os.path.dirname(os.path.realpath(run))), "data",
                        os.path.basename(run.rstrip("/")).rsplit("_", 1)[0])
    for v in views:
        photo = tile(os.path.join(data, "images", f"view_{v:03d}.png"))
        rows.append(np.concatenate([photo] + [tile(os.path.join(run, "previews", f"view{v:03d}_{k}.png"))
                                              for k in ("full", "depth", "bg", "fg")], 1))
Image.fromarray(np.concatenate(rows, 0)).save(out)
