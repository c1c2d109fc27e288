"""OpenCV's FSR on the statue's first six views (their masks grown by 4 pixels): one view at a time against
two threads (seconds, and whether the pixels agree).

    python fsr_threads.py [../shared/data/statue]
"""
import glob
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import cv2
import numpy as np
from PIL import Image

from mi_voldis.inpaint2d import fsr_inpaint

root = sys.argv[1] if len(sys.argv) > 1 else os.path.join("..", "shared", "data", "statue")
views = []
for path in sorted(glob.glob(os.path.join(root, "images_2", "*.png")))[:6]:
    image = np.asarray(Image.open(path).convert("RGB"), np.float32) / 255
    label = np.asarray(Image.open(os.path.join(root, "images_2", "label", os.path.basename(path))))
    hole = (label[..., 0] if label.ndim == 3 else label) > 0
    views.append((image, cv2.dilate(hole.astype(np.uint8), np.ones((9, 9), np.uint8)) > 0))
t = time.perf_counter()
one = [fsr_inpaint(*v) for v in views]
print(f"one at a time: {time.perf_counter() - t:.1f} s")
t = time.perf_counter()
with ThreadPoolExecutor(2) as pool:
    two = list(pool.map(lambda v: fsr_inpaint(*v), views))
same = all(np.array_equal(a, b) for a, b in zip(one, two))
print(f"two threads: {time.perf_counter() - t:.1f} s, same pixels: {same}")
