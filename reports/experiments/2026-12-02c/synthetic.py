"""#46: `seen_surface_tol` on the test suite's synthetic sphere (a red haze round it in the full field, as fits
leave): the guided refit (`tests/test_background.py::guided_removal`) scored by the removal bench's `evaluate`
against the scene's truth, every seen vertex kept (0) and the rule (0.015), `keep_seen_gap` 0 and 1.

    python reports/experiments/2026-12-02c/synthetic.py        # from the repository root
"""
import dataclasses
import os
import pathlib
import sys
import tempfile

import numpy as np

root = os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 3))
sys.path[:0] = [root, os.path.join(root, "tests")]

from test_background import guided_removal  # noqa: E402

from mi_voldis.bench.strategies import evaluate  # noqa: E402
from mi_voldis.fit.fields import fit_integrator  # noqa: E402

for tol in (0.0, 0.015):
    for gap in (0, 1):
        with tempfile.TemporaryDirectory() as work:
            ds, _, inputs, state = guided_removal(pathlib.Path(work), keep_seen=True, keep_seen_gap=gap,
                                                  seen_surface_tol=tol)
            truth, _ = evaluate(dataclasses.replace(ds, coverage=ds.masks.astype(np.float32)),
                                fit_integrator(inputs, state))
        v = truth["volume"]
        print(f"seen_surface_tol {tol}, keep_seen_gap {gap}: "
              + ", ".join(f"{k} {v[k]:.3f}" for k in ("psnr_mask", "residue", "fg_coverage_iou", "fg_matte_iou")))
