"""Bytes a stored vertex costs at each colour layout: the full phase's peak resident set (phase_peaks.py's
'[peak] ... optimize (full)' line in RUN.log) against the vertices the run stored (metrics.json), fitted as
base + vertices * per_float * packet width by least squares.

    python reports/experiments/2026-11-28/grey_sh/per_vertex.py RUN [RUN ...]
"""
import json
import os
import re
import sys

import numpy as np


def main(*runs):
    rows = []
    for run in runs:
        with open(os.path.join(run, "metrics.json")) as f:
            m = json.load(f)
        with open(run + ".log") as f:
            peak = float(re.search(r"\[peak\].*optimize \(full\)\s+(\d+) MiB", f.read()).group(1))
        grid = np.load(os.path.join(run, "full_grid.npz"))
        width = 1 << int(np.ceil(np.log2(grid["data"].shape[-1])))
        rows.append((os.path.basename(run), m["bricks"]["full"]["vertices"], width, peak))
    a = np.array([[1.0, v * w] for _, v, w, _ in rows])
    base, per_float = np.linalg.lstsq(a, np.array([p for *_, p in rows]) * 2 ** 20, rcond=None)[0]
    print(f"fit: base {base / 2 ** 20:.0f} MiB, {per_float:.1f} bytes a packed float")
    for name, v, w, p in rows:
        model = (base + per_float * v * w) / 2 ** 20
        print(f"{name}: {v} vertices, packet width {w}, full-phase peak {p:.0f} MiB (fit {model:.0f}), "
              f"{per_float * w:.0f} bytes a vertex")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(*sys.argv[1:])
