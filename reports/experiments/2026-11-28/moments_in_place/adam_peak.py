"""Adam's step on one grid-sized array: the package's optimiser (moments and values written as three new arrays)
against the trial beside this script (``adam_in_place.diff``, applied to a copy of it: the moments written in
place), each in a process of its own, in turns. Dr.Jit's allocator figures after 8 steps ("in use / held
(peak)", ``dr.whos()``), the median time of steps 3-8 (kernel evaluated), and the last value, which both must
give alike (reports/notes.md).

    python reports/experiments/2026-11-28/moments_in_place/adam_peak.py [FLOATS [WIDTH [ROUNDS]]]

FLOATS (default 45 M: the statue's 472^3 at degree 0), WIDTH the packed floats a vertex (4; degree 1: 16).
"""
import contextlib
import importlib.util
import io
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, *[".."] * 4))


def trial_adam():
    """mi_voldis/optim/adam.py with adam_in_place.diff applied, in a folder of its own, loaded as a module."""
    with tempfile.TemporaryDirectory() as folder:
        os.makedirs(os.path.join(folder, "mi_voldis", "optim"))
        path = os.path.join(folder, "mi_voldis", "optim", "adam.py")
        shutil.copy(os.path.join(ROOT, "mi_voldis", "optim", "adam.py"), path)
        subprocess.run(["git", "apply", os.path.join(HERE, "adam_in_place.diff")], cwd=folder, check=True)
        with open(path) as f:
            source = f.read().replace("from ..device", "from mi_voldis.device")
        with open(path, "w") as f:
            f.write(source)
        spec = importlib.util.spec_from_file_location("adam_in_place", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    return module


def one(version, n, width):
    sys.path.insert(0, ROOT)
    import drjit as dr
    import mitsuba as mi
    import numpy as np
    mi.set_variant("llvm_ad_rgb")
    if version == "package":
        from mi_voldis.optim import adam as module
    else:
        module = trial_adam()
    params = {"x": dr.arange(mi.Float, n) * 1e-9}
    dr.eval(params["x"])
    adam = module.Adam({"x": [0.1] + [0.05] * (width - 1)}, warmup=10)
    times = []
    for t in range(8):
        g = dr.arange(mi.Float, n) * 1e-9 + t
        dr.eval(g)
        dr.sync_thread()
        t0 = time.perf_counter()
        adam.step(params, {"x": g})
        dr.eval(params["x"], adam.m["x"], adam.v["x"])
        dr.sync_thread()
        times.append(time.perf_counter() - t0)
        del g
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        dr.whos()
    memory = [s.split(":", 1)[1].strip() for s in buf.getvalue().splitlines() if "used" in s][0]
    print(f"{version:>8} ({n / 1e6:.1f} M floats, width {width}): a step {1e3 * np.median(times[2:]):.1f} ms, "
          f"{memory} last value {float(np.array(params['x'])[-1]):.9g}", flush=True)


def main(argv):
    if argv and argv[0] == "--one":
        return one(argv[1], int(argv[2]), int(argv[3]))
    n = int(float(argv[0])) if argv else 45_000_000
    width = int(argv[1]) if len(argv) > 1 else 4
    rounds = int(argv[2]) if len(argv) > 2 else 2
    for _ in range(rounds):
        for version in ("package", "in place"):
            subprocess.run([sys.executable, __file__, "--one", version, str(n), str(width)], check=True)


if __name__ == "__main__":
    main(sys.argv[1:])
