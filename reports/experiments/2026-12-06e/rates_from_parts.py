"""The llvm rates for bricks of 4 from two captures' step timings side by side (`brick_parts.py`), one
float-heavy (the statue) and one sample-heavy (garden): per brick size, the seconds a sample x and a stored float
y on this machine solving  t = x S + y F  for both captures (medians of the rounds), then the package's bricks-of-8
rates (168 ns, 1.86 ns at the reference) scaled by bricks of 4's x and y over bricks of 8's.

    python reports/experiments/2026-12-06e/rates_from_parts.py ../2026-12-06d/brick_parts_552.txt brick_parts_garden.txt
"""
import re
import statistics
import sys

import numpy as np

ROW = re.compile(r"brick (\d+) at \d+\^3: ([\d.]+) ms a step, (\d+) k samples, ([\d.]+) M floats")


def medians(path):
    rows = {}
    for line in open(path):
        m = ROW.search(line)
        if m:
            rows.setdefault(int(m[1]), []).append((float(m[2]) * 1e-3, float(m[3]) * 1e3, float(m[4]) * 1e6))
    return {b: tuple(statistics.median(r[i] for r in rs) for i in range(3)) for b, rs in rows.items()}


caps = [medians(p) for p in sys.argv[1:3]]
rates = {}
for brick in (8, 4):
    a = np.array([[c[brick][1], c[brick][2]] for c in caps])
    t = np.array([c[brick][0] for c in caps])
    x, y = np.linalg.solve(a, t)
    rates[brick] = (x, y)
    print(f"bricks of {brick}: {x * 1e9:.1f} ns a sample, {y * 1e9:.3f} ns a float on this machine "
          f"(ratio {x / y:.1f}; the package's bricks-of-8 rates: {168 / 1.86:.1f})")
sx, sf = rates[4][0] / rates[8][0], rates[4][1] / rates[8][1]
print(f"bricks of 4 over 8: samples x{sx:.3f}, floats x{sf:.3f}: sample_ns {168 * sx:.2f}, float_ns {1.86 * sf:.3f}")
for name, c in zip(sys.argv[1:3], caps):
    s, f = c[4][1], c[4][2]
    new, now = (s * 168 * sx + f * 1.86 * sf) * 1e-9, (s * 178.25 + f * 1.973) * 1e-9
    print(f"{name}: bricks of 4's step counted {new * 1e3:.1f} ms at these rates, {now * 1e3:.1f} at 178.25 / 1.973")
