"""Where a fit's memory goes: the default training command with the resident set size and Dr.Jit's own
allocation statistics printed at each stage start (before and after the fields are refined) and at the
end, optionally releasing Dr.Jit's allocation cache after every refinement.

    python reports/experiments/2026-11-27/memory/rss_trace.py [--flush] -- DATASET --out RUN [train.py flags]
"""
import os
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4))
sys.path.insert(0, ROOT)

import drjit as dr  # noqa: E402

from mi_voldis.fit import problem  # noqa: E402

WHOS_AT = (850,)  # steps whose live arrays are listed


def rss_mib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20


def main():
    argv = sys.argv[1:]
    flush = "--flush" in argv[: argv.index("--")] if "--" in argv else False
    rest = argv[argv.index("--") + 1:] if "--" in argv else argv
    original = problem.refine

    def traced(inputs, state, integrator, roles, resolution, *bounds):
        print(f"[rss] before refine to {resolution}: {rss_mib():.0f} MiB", flush=True)
        used = original(inputs, state, integrator, roles, resolution, *bounds)
        if flush:
            dr.flush_malloc_cache()
        vertices = sum(state.fields[r].vertices for r in roles)
        print(f"[rss] after refine to {used[0]}: {rss_mib():.0f} MiB, {vertices} vertices", flush=True)
        return used

    problem.refine = traced
    after = problem.FieldFit.after_step

    def after_step(self, step):  # what Dr.Jit holds mid-stage
        after(self, step)
        if step in WHOS_AT:
            print(f"[rss] step {step}: {rss_mib():.0f} MiB; Dr.Jit's live arrays:", flush=True)
            dr.whos()
            sys.stdout.flush()

    problem.FieldFit.after_step = after_step
    from voldis_cli.train import main as train_main
    try:
        train_main(rest)
    finally:
        print(f"[rss] end: {rss_mib():.0f} MiB", flush=True)


if __name__ == "__main__":
    main()
