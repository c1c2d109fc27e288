"""Where a fit's seconds go after its full phase, from a py-spy raw profile of the whole run
(`py-spy record -r 10 -f raw -o FILE -- python scripts/train.py ...`): seconds per part of the background
refit's set-up and the rest, and below each part its three heaviest callees.

    python bg_seconds.py FILE [FILE ...]
"""
import collections
import sys

PARTS = ("object_fringe", "start_harmonic", "find_shadow", "effect_cells", "background_ray_pool", "colour_prior",
         "optimize", "clear_empty_background_color", "evaluate")

for path in sys.argv[1:]:
    rate = 10.0  # samples a second
    total, parts, inner = 0, collections.Counter(), collections.defaultdict(collections.Counter)
    for line in open(path):
        stack, _, n = line.rstrip().rpartition(" ")
        names = [f.split(" (")[0] for f in stack.split(";")]
        total += int(n)
        if "fit_full" in names:
            parts["full phase"] += int(n)
            continue
        part = next((p for p in PARTS if p in names), "other")
        parts[part] += int(n)
        if part != "other":
            i = names.index(part)
            inner[part][" / ".join(names[i + 1:i + 3])] += int(n)
    print(f"{path}: {total / rate:.0f} s sampled")
    for part, n in parts.most_common():
        print(f"  {part:30s} {n / rate:7.1f} s")
        for callee, m in inner[part].most_common(3):
            print(f"      {m / rate:7.1f}  {callee}")
