"""#42: a training step with a 64^3 view lattice over the same brick grid's without one, side by side
(alternating blocks of steps), on fitting's tiled batches of 8192 rays:

    python reports/experiments/2026-11-29g/gloss_keep_seen/view_step_cost.py
"""
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
from mi_voldis.bench import throughput  # noqa: E402

for r, n, b in [(128, 128, 8192), (256, 96, 8192)]:
    impls = {k: throughput.step_functions(r, n, b, rays="tiles", representation=k) for k in ("bricks", "view")}
    t = throughput.interleaved(impls, 8, {"bricks": 2, "view": 2}, rounds=2)
    print(f"{r}^3, {n} samples/ray, {b} rays: training step {t['view']['train']['seconds']:.4f} s with the lattice, "
          f"{t['bricks']['train']['seconds']:.4f} s without "
          f"({t['view']['train']['seconds'] / t['bricks']['train']['seconds']:.2f}x); forward "
          f"{t['view']['forward']['seconds'] / t['bricks']['forward']['seconds']:.2f}x", flush=True)
