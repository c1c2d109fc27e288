"""Resident memory of a capture's dataset and of its training ray bank, as a fit builds them.

    python reports/experiments/2026-12-06i/bank_rss.py ../shared/data/garden
"""
import sys

import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")

from mi_voldis.data import load_dataset  # noqa: E402
from mi_voldis.raybank import RayBank  # noqa: E402


def rss_mib():
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS:")) / 1024


before = rss_mib()
ds = load_dataset(sys.argv[1])
loaded = rss_mib()
bank = RayBank(ds, ds.train)
dr.eval(bank.codes if bank.codes is not None else bank.colors)
banked = rss_mib()
layout = f"{bank.bits}-bit codes" if bank.codes is not None else "floats"
print(f"{ds!r}: {bank.pixels} training pixels; dataset {loaded - before:.0f} MiB, bank ({layout}) "
      f"{banked - loaded:.0f} MiB = {(banked - loaded) * 2 ** 20 / bank.pixels:.1f} bytes a pixel")
