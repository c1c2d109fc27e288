"""A scene's held-out backgrounds against the truth, before and after: columns truth, then for each removal folder
its background and |error| x 4; rows the held-out views 0, 8, 16, 24. Prints each view's PSNR inside the mask grown
by 5 pixels (on the 8-bit previews: near the bench's figure, not it).

    python error_sheet.py DATASET OUT.png REMOVAL_BEFORE REMOVAL_AFTER     # REMOVAL: .../removal/familyNN/guided
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
    raise SystemExit(f"error_sheet.py: {out} exists; give a new file")
rows = []
for v in (0, 8, 16, 24):
    truth = np.array(Image.open(f"{data}/backgrounds/view_{v:03d}.png").convert("RGB")) / 255.0
    mask = np.array(Image.open(f"{data}/masks/view_{v:03d}.png").convert("L")) > 127
    grown = cv2.dilate(mask.astype(np.uint8), np.ones((11, 11), np.uint8)) > 0
    row, line = [truth], [f"view {v}:"]
    for folder in folders:
        bg = np.array(Image.open(f"{folder}/view{v:03d}_bg.png").convert("RGB")) / 255.0
        line.append(f"{-10 * np.log10(((bg - truth) ** 2)[grown].mean()):.2f} dB")
        row += [bg, np.repeat(np.clip(4 * np.abs(bg - truth).mean(-1), 0, 1)[..., None], 3, -1)]
    rows.append(np.concatenate(row, 1))
    print(" ".join(line))
Image.fromarray((np.concatenate(rows, 0) * 255).round().astype(np.uint8)).save(out)
