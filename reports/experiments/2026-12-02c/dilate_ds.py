"""#46: a family dataset's copy (links to its files) whose masks are dilated by K pixels (an elliptic kernel);
DST must not exist.

    python dilate_ds.py DATASET DST K
"""
import os
import sys

import cv2
import numpy as np
from PIL import Image

src, dst, k = sys.argv[1], sys.argv[2], int(sys.argv[3])
if os.path.lexists(dst):  # a copy of its own, never into a folder already there (the dataset itself)
    raise SystemExit(f"dilate_ds.py: {dst} exists; give a new folder")
os.makedirs(dst)
for name in os.listdir(src):
    if name != "masks":
        os.symlink(os.path.join(src, name), os.path.join(dst, name))
os.makedirs(os.path.join(dst, "masks"))
kern = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * k + 1, 2 * k + 1))
for name in sorted(os.listdir(os.path.join(src, "masks"))):
    m = np.array(Image.open(os.path.join(src, "masks", name)).convert("L")) > 127
    d = cv2.dilate(m.astype(np.uint8), kern) > 0
    Image.fromarray((d * 255).astype(np.uint8)).save(os.path.join(dst, "masks", name))
