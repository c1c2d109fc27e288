"""Held-out views of several fitted runs side by side (full layer), photo first, with each view's PSNR printed.

    python sheet.py OUT.png VIEWS RUN [RUN ...]     e.g. sheet.py out.png 16,64,112 runA runB
"""
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")

from mi_voldis.io.images import write_png  # noqa: E402
from mi_voldis.metrics import psnr  # noqa: E402
from mi_voldis.render.views import render_camera  # noqa: E402
from mi_voldis.tasks.base import FittedRun  # noqa: E402

out, views, runs = sys.argv[1], [int(v) for v in sys.argv[2].split(",")], [FittedRun(r) for r in sys.argv[3:]]
ds = runs[0].dataset
rows = []
for v in views:
    row = [ds.images[v]]
    for name, run in zip(sys.argv[3:], runs):
        full = render_camera(run.integrator(), ds.cameras[v], ("full",))["full"]
        img = np.clip(run.dataset.as_photographed(full), 0, 1)
        print(f"view {v} {name}: {psnr(img, ds.images[v]):.2f} dB", flush=True)
        row.append(img)
    rows.append(np.concatenate(row, axis=1))
write_png(out, (np.concatenate(rows, axis=0) * 255 + 0.5).astype(np.uint8))
