"""What a capture's training ray bank holds on the device, as the bank lays it out now (8-bit photographs packed
one UInt32 a pixel; float ones as floats, with no mask array where the capture has no masks) against the float
layout it had before (three colour floats and a float mask a pixel, a mask of zeros where there are none): how
much the process's resident set grows as each is built (arrays made from NumPy do not show in Dr.Jit's
allocator figures) (reports/notes.md).

    python reports/experiments/2026-11-28/ray_bank/bank_memory.py DATASET...
"""
import os
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4))
sys.path.insert(0, ROOT)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("llvm_ad_rgb")
from mi_voldis.data import load_dataset  # noqa: E402
from mi_voldis.raybank import RayBank  # noqa: E402


def rss_mib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20


def main(paths):
    for path in paths:
        ds = load_dataset(path)
        pixels = len(ds.train) * ds.size[0] * ds.size[1]
        start = rss_mib()
        bank = RayBank(ds, ds.train)
        layout = "8-bit, packed" if bank.codes is not None else (
            "float, no mask array" if bank.masks is None else "float with masks")
        now = rss_mib() - start
        del bank
        dr.flush_malloc_cache()
        # the float layout as it was: a value off the 8-bit levels forces floats, a mask of zeros where none
        ds.images = ds.images.copy()
        ds.images[ds.train[0], 0, 0, 0] = np.nextafter(ds.images[ds.train[0], 0, 0, 0], np.float32(2))
        if ds.masks is None:
            ds.masks = np.zeros((len(ds.images),) + tuple(ds.size), bool)
        start = rss_mib()
        before = RayBank(ds, ds.train)
        print(f"{os.path.basename(path.rstrip('/'))}: {len(ds.train)} training views, {pixels / 1e6:.1f} M pixels; "
              f"now ({layout}) +{now:.0f} MiB, the float layout +{rss_mib() - start:.0f} MiB", flush=True)
        del before, ds
        dr.flush_malloc_cache()


if __name__ == "__main__":
    main(sys.argv[1:])
