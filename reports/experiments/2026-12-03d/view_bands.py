"""Where a held-out view's error lies: PSNR of a rendered PNG against the photo in horizontal bands, each band's
share of the squared error, and the PSNR without the top rows.

usage: python view_bands.py PHOTO RENDER [BANDS] [TOP_ROWS]   # BANDS default 9, TOP_ROWS default 42
"""
import sys

import numpy as np
from PIL import Image

if len(sys.argv) not in (3, 4, 5):
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
try:
    photo, render = (np.asarray(Image.open(p).convert("RGB"), float) / 255 for p in sys.argv[1:3])
except OSError as e:
    raise SystemExit(f"view_bands.py: {e}") from None
if photo.shape != render.shape:
    raise SystemExit(f"view_bands.py: {sys.argv[2]} is {render.shape[1]}x{render.shape[0]}, the photo "
                     f"{photo.shape[1]}x{photo.shape[0]}")
counts = sys.argv[3:] + ["9", "42"][len(sys.argv) - 3:]
if not all(c.isdigit() and int(c) > 0 for c in counts):
    raise SystemExit(f"view_bands.py: BANDS and TOP_ROWS must be whole numbers above 0, got {' '.join(counts)}")
bands, top = (int(c) for c in counts)
if bands > photo.shape[0] or top >= photo.shape[0]:
    raise SystemExit(f"view_bands.py: the photo has {photo.shape[0]} rows: BANDS {bands} or TOP_ROWS {top} too many")
err = ((photo - render) ** 2).mean(axis=2)
print(f"whole view {-10 * np.log10(err.mean()):.2f} dB")
for rows in np.array_split(np.arange(err.shape[0]), bands):
    band = err[rows]
    print(f"rows {rows[0]:4d}-{rows[-1]:4d}: {-10 * np.log10(band.mean()):6.2f} dB, "
          f"{band.sum() / err.sum():.3f} of the squared error")
print(f"without the top {top} rows: {-10 * np.log10(err[top:].mean()):.2f} dB")
