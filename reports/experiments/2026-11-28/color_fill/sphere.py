"""The test suite's synthetic sphere (tests/test_background.py, ``guided_removal``: 30 refit steps) removed
with ``hull_color_fill`` off and on, scored as the removal bench scores (held-out views, in the mask and
outside it, the foreground's coverage and matte IoU against the masks).

    python reports/experiments/2026-11-28/color_fill/sphere.py
"""
import dataclasses
import os
import pathlib
import sys
import tempfile

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4))
sys.path[:0] = [ROOT, os.path.join(ROOT, "tests")]

from test_background import guided_removal  # noqa: E402

from mi_voldis.bench.strategies import evaluate  # noqa: E402
from mi_voldis.fit.fields import fit_integrator  # noqa: E402

for on in (False, True):
    with tempfile.TemporaryDirectory() as tmp:
        ds, _, inputs, state = guided_removal(pathlib.Path(tmp), keep_seen=True, keep_seen_gap=0, hull_color_fill=on)
        rows, _ = evaluate(dataclasses.replace(ds, coverage=ds.masks.astype(np.float32)), fit_integrator(inputs, state),
                           0.03)
    v = rows["volume"]
    print(f"hull_color_fill={str(on).lower()}: in the mask {v['psnr_mask']:.2f} dB, "
          f"outside {v['psnr_outside']:.2f} dB, coverage IoU {v['fg_coverage_iou']:.3f}, "
          f"matte IoU {v['fg_matte_iou']:.3f}", flush=True)
