"""Two sets of row lines (rows.py's output, files A and B) side by side: margin and consistency change
per scene, and each half's worst margin (scenes 0-9 tune, 10-19 check).

    python reports/experiments/2026-11-28/color_fill/compare.py A.txt B.txt
"""
import re
import sys

LINE = re.compile(r"(family\d+)\S*\s+mask ([\d.]+) margin ([+-][\d.]+) iou ([\d.]+) cons ([\d.]+)")


def load(path):
    rows = {}
    with open(path) as f:
        for line in f:
            m = LINE.search(line)
            if m:
                rows[m.group(1)] = [float(x) for x in m.groups()[1:]]
    return rows


def main(a_path, b_path):
    a, b = load(a_path), load(b_path)
    both = sorted(set(a) & set(b))
    print("| scene | margin A | margin B | change | consistency change | coverage IoU change |")
    print("|---|---|---|---|---|---|")
    for s in both:
        print(f"| {s} | {a[s][1]:+.2f} | {b[s][1]:+.2f} | {b[s][1] - a[s][1]:+.2f} | {b[s][3] - a[s][3]:+.2f} "
              f"| {b[s][2] - a[s][2]:+.3f} |")
    for half, lo, hi in (("tuning", 0, 10), ("check", 10, 20)):
        ks = [s for s in both if lo <= int(s[6:]) < hi]
        if ks:
            wa, wb = min(ks, key=lambda s: a[s][1]), min(ks, key=lambda s: b[s][1])
            print(f"\n{half} half ({len(ks)} scenes): worst A {wa} {a[wa][1]:+.2f}, worst B {wb} {b[wb][1]:+.2f}; "
                  f"B higher on {sum(b[s][1] > a[s][1] for s in ks)}, consistency higher on "
                  f"{sum(b[s][3] > a[s][3] for s in ks)}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit("usage: python compare.py A.txt B.txt")
    main(*sys.argv[1:])
