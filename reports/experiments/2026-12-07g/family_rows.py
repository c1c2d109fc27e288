"""The session's family rows (row `guided`), per scene: python family_rows.py WORK [BASE.json]

WORK: the folder of the session's bench `--work` folders (`/work/runs/s66`); each folder's name says what was
fitted (RULES). BASE: the committed family report (reports/family.json, 2026-12-02's code) shown first.
Columns: margin over the better of Telea / Navier-Stokes in the mask, consistency margin, coverage IoU, haze in
the hole / outside, in-mask PSNR of the background layer.
"""
import glob
import json
import os
import sys

from mi_voldis.bench.family import scene_row

ERODED, GAPS = "free_space, mask eroded by a pixel (5bbba03)", "free_space, reach off the mask's gaps (bdfed5f)"
RULES = {"defC": "default (5bbba03)", "fsA": ERODED, "fsB": ERODED, "fsE": "free_space, a vertex's reach (885b551)",
         "gD": GAPS, "gE": GAPS}


def row(r):
    c = r["consistency_margin"]
    return (f"{r['margin']:+6.2f} {'-' if c is None else f'{c:+6.2f}':>6} {r['coverage_iou']:.2f} "
            f"{r['haze_mask']:.3f}/{r['haze_outside']:.3f} {r['psnr_mask']:.2f}")


def main():
    work = sys.argv[1]
    base = json.load(open(sys.argv[2])) if len(sys.argv) > 2 else None
    rows = {}
    for src in RULES:
        for p in sorted(glob.glob(os.path.join(work, src, "removal", "*", "guided", "metrics.json"))):
            with open(p) as f:
                entry = {"strategies": {"guided": json.load(f)}}
            rows.setdefault(p.split(os.sep)[-3], []).append((src, scene_row(entry, "guided")))
    print("margin, consistency margin, coverage IoU, haze in hole / outside, in-mask PSNR")
    for scene in sorted(rows):
        print(scene)
        if base and scene in base["scenes"]:
            print(f"  {'report of 2026-12-02':48s} {row(scene_row(base['scenes'][scene], 'guided'))}")
        for src, r in rows[scene]:
            print(f"  {RULES[src]:48s} {row(r)}")


if __name__ == "__main__":
    main()
