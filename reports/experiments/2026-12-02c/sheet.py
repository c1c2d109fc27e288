"""#46: a family scene's held-out backgrounds beside the photo, the truth and OpenCV's Telea (the mask grown by 3
pixels), cropped round the mask and enlarged 4x; rows the held-out views 0, 8, 16, 24. Prints each view's PSNR in
that grown mask (8-bit previews: near the bench's figure, not it), Telea's first.

    python sheet.py DATASET OUT.png REMOVAL...     # REMOVAL: .../removal/familyNN/guided
"""
import os
import sys

import cv2
import numpy as np
from PIL import Image

if len(sys.argv) < 4:
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
data, out, folders = sys.argv[1], sys.argv[2], sys.argv[3:]
if os.path.lexists(out):  # a sheet of its own, never a file already there
    raise SystemExit(f"sheet.py: {out} exists; give a new file")
rows = []
for v in (v for v in (0, 8, 16, 24) if os.path.isfile(f"{data}/backgrounds/view_{v:03d}.png")):
    truth = np.array(Image.open(f"{data}/backgrounds/view_{v:03d}.png").convert("RGB"))
    img = np.array(Image.open(f"{data}/images/view_{v:03d}.png").convert("RGB"))
    mask = np.array(Image.open(f"{data}/masks/view_{v:03d}.png").convert("L")) > 127
    grown = cv2.dilate(mask.astype(np.uint8), np.ones((7, 7), np.uint8))
    tel = cv2.inpaint(img[..., ::-1].copy(), grown, 3, cv2.INPAINT_TELEA)[..., ::-1]
    row = [img, truth, tel]
    line = [f"view {v}: telea {-10 * np.log10((((tel / 255. - truth / 255.) ** 2)[grown > 0]).mean()):.2f}"]
    for f in folders:
        bg = np.array(Image.open(f"{f}/view{v:03d}_bg.png").convert("RGB"))
        line.append(f"{-10 * np.log10((((bg / 255. - truth / 255.) ** 2)[grown > 0]).mean()):.2f}")
        row.append(bg)
    ys, xs = np.nonzero(grown)
    y0, y1, x0, x1 = max(ys.min() - 8, 0), ys.max() + 8, max(xs.min() - 8, 0), xs.max() + 8
    row = [cv2.resize(r[y0:y1, x0:x1], None, fx=4, fy=4, interpolation=cv2.INTER_NEAREST) for r in row]
    h, w = max(r.shape[0] for r in row), max(r.shape[1] for r in row)
    row = [np.pad(r, ((0, h - r.shape[0]), (0, w - r.shape[1]), (0, 0))) for r in row]
    rows.append(np.concatenate(row, 1))
    print(" ".join(line))
w = max(r.shape[1] for r in rows)
rows = [np.pad(r, ((0, 0), (0, w - r.shape[1]), (0, 0))) for r in rows]
Image.fromarray(np.concatenate(rows, 0)).save(out)
