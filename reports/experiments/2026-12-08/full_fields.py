"""#46: each family scene's full field held out (dB), default against free_space=true, and the free vertices of
the told fit's last stage (its kept checkpoint's `free`): python full_fields.py ALL
ALL: the folder of `link.sh` (ALL/def/SCENE and ALL/told/SCENE, each a `bench.py --family` folder)."""
import json
import os
import sys

import numpy as np

root = sys.argv[1]


def run_of(kind, scene):
    return os.path.join(root, kind, scene, "work", "runs", f"{scene}_0")


for scene in sorted(os.listdir(os.path.join(root, "told"))):
    cells = []
    for kind in ("def", "told"):
        path = os.path.join(run_of(kind, scene), "metrics.json")
        if os.path.isfile(path):
            with open(path) as f:
                cells.append(f"{kind} {json.load(f)['held_out']['psnr']:.2f}")
    last = os.path.join(run_of("told", scene), "checkpoints", "last.npz")
    if os.path.isfile(last):
        with np.load(last) as f:
            cells.append(f"free vertices {len(f['free']) if 'free' in f.files else 0:,}")
    print(scene, ", ".join(cells))
