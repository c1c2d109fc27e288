"""Dr.Jit's allocator on a bare array: the block an evaluated array takes (rounded up to a power of two).

    python reports/experiments/2026-11-27/memory/allocator_rounding.py
"""
import contextlib
import io

import drjit as dr
import mitsuba as mi


def held():
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        dr.whos()
    return [s for s in buf.getvalue().splitlines() if "used" in s][0].split(":", 1)[1].strip()


def main():
    mi.set_variant("llvm_ad_rgb")
    for floats in (58_984_448, 38_000_000):
        x = dr.arange(mi.Float, floats)
        dr.eval(x)
        print(f"{floats * 4 / 2 ** 20:.0f} MiB of floats: {held()}")
        del x
        dr.flush_malloc_cache()


if __name__ == "__main__":
    main()
