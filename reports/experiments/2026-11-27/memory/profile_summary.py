"""Seconds per function (inclusive) of a py-spy raw profile, the top N:

    py-spy record -r 20 -f raw -o PROF -- python scripts/train.py DATASET --out RUN
    python reports/experiments/2026-11-27/memory/profile_summary.py PROF [RATE] [N]
"""
import collections
import sys


def main(path, rate=20, top=60):
    total = collections.Counter()
    for line in open(path):
        line = line.rstrip()
        if not line:
            continue
        stack, count = line.rsplit(" ", 1)
        seen = set()
        for frame in stack.split(";"):
            name = frame.split(" (")[0]
            if name not in seen:
                seen.add(name)
                total[name] += int(count)
    for name, count in total.most_common(int(top)):
        print(f"{count / float(rate):7.1f} s  {name}")


if __name__ == "__main__":
    main(*sys.argv[1:])
