"""Where in a fit its memory peaks: the training command with the resident set sampled every 0.2 s and the
peak reported per part of the fit (the full phase's steps, the background's start: hull, shadow search,
colour prior, ray pool; its steps; the end).

    python reports/experiments/2026-11-27/memory/phase_peaks.py [--flush] -- DATASET --out RUN [train.py flags]

--flush: release Dr.Jit's allocation cache (and collect Python's garbage) after each of those parts.
"""
import gc
import os
import sys
import threading
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4))
sys.path.insert(0, ROOT)

import drjit as dr  # noqa: E402

from mi_voldis.fit import train  # noqa: E402

PARTS = ("start_harmonic", "find_shadow", "colour_prior", "background_ray_pool", "optimize",
         "clear_empty_background_color")


def rss_mib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20


def main():
    rest = sys.argv[sys.argv.index("--") + 1:]
    flush = "--flush" in sys.argv[1:sys.argv.index("--")]
    samples, marks, done = [], [], threading.Event()

    def sample():
        while not done.is_set():
            samples.append((time.perf_counter(), rss_mib()))
            time.sleep(0.2)

    def wrap(name, fn):
        def inner(*a, **k):
            marks.append((time.perf_counter(), f"{name}" + (f" ({k.get('desc')})" if k.get("desc") else "")))
            try:
                return fn(*a, **k)
            finally:
                if flush:
                    gc.collect()
                    dr.flush_malloc_cache()
                marks.append((time.perf_counter(), f"after {name}"))
        return inner

    for name in PARTS:
        setattr(train, name, wrap(name, getattr(train, name)))
    threading.Thread(target=sample, daemon=True).start()
    from voldis_cli.train import main as train_main
    try:
        train_main(rest)
    finally:
        done.set()
        marks.append((time.perf_counter(), "end"))
        t0 = samples[0][0] if samples else 0
        bounds = [(t0, "start")] + marks
        for (a, label), (b, _) in zip(bounds, bounds[1:]):
            inside = [r for t, r in samples if a <= t < b]
            if inside:
                print(f"[peak] {a - t0:7.1f}-{b - t0:7.1f} s {label:40s} {max(inside):7.0f} MiB", flush=True)


if __name__ == "__main__":
    main()
