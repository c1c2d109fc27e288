"""Machine facts for benchmark reports: CPU, versions, memory bandwidth and the bound it sets.

Bandwidth is measured with a large copy (read + write counted) by NumPy (one thread) and by a Dr.Jit
kernel (all threads). A density + RGB trilinear lookup touches 8 corners x 4 floats = 128 bytes; a
training sample touches three times that (the forward lookup and the read-modify-write of the
gradient scatter) plus its 16-byte record written and read back (the adjoint replays recorded values,
:class:`mi_voldis.render.march.Record`), which gives the bandwidth bound on samples per second.
"""
import os
import platform
import subprocess
import time

import drjit as dr
import mitsuba as mi
import numpy as np

BYTES_FORWARD = 8 * 4 * 4
BYTES_TRAIN = 3 * BYTES_FORWARD + 2 * 16
BYTES_TABLE = 8 * 4  # a brick grid's lookup reads the brick table at each corner


def describe():
    cpu = platform.processor() or ""
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        cpu = next((line.split(":", 1)[1].strip() for line in out.splitlines() if line.startswith("Model name")), cpu)
    except OSError:
        pass
    versions = {"python": platform.python_version(), "mitsuba": mi.__version__, "drjit": dr.__version__,
                "numpy": np.__version__}
    try:
        import torch
        versions["torch"] = torch.__version__
    except ImportError:
        pass
    return {"cpu": cpu, "cores": os.cpu_count(), "system": platform.platform(), "variant": mi.variant(),
            "versions": versions}


def copy_bandwidth(gib=1.0, repeats=3):
    """GB/s of a large copy (2 x bytes moved per copy): NumPy (one thread) and Dr.Jit (all threads)."""
    n = int(gib * (1 << 30) // 4)
    src = np.ones(n, np.float32)
    dst = np.empty_like(src)
    best_np = min(_timed(lambda: np.copyto(dst, src)) for _ in range(repeats))
    x = dr.arange(mi.Float, n)  # an evaluated array (dr.full would stay a literal: no memory to read)
    dr.eval(x)

    def jit_copy():
        y = x * 1.5
        dr.eval(y)
        dr.sync_thread()
    jit_copy()
    best_jit = min(_timed(jit_copy) for _ in range(repeats))
    moved = 2 * 4 * n / 1e9
    return {"numpy_gbs": moved / best_np, "drjit_gbs": moved / best_jit}


def _timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t
