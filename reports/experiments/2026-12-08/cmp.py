"""Held-out views 0, 8 and 16 of each refit's background, one row a folder, twice the size:
python cmp.py OUT.png DIR [DIR ...] (refuses an existing OUT)."""
import os
import sys

import cv2
import numpy as np

if os.path.lexists(sys.argv[1]):
    raise SystemExit(f"error: {sys.argv[1]} exists; give another OUT")
rows = [np.hstack([cv2.imread(os.path.join(d, f"view{v:03d}_bg.png")) for v in (0, 8, 16)]) for d in sys.argv[2:]]
cv2.imwrite(sys.argv[1], cv2.resize(np.vstack(rows), None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST))
