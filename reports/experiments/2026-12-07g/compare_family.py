"""Two family reports side by side, row `guided`: python compare_family.py BASE.json TRIAL.json [TRIAL2.json ...]

BASE: a family.json (the default's); TRIAL: one or more family.json of the same scenes fitted with a `--set`
(several are merged: the scenes were split over clones). Prints each scene's margin over the better of Telea /
Navier-Stokes in the mask, consistency margin, coverage IoU and haze in the hole / outside, then each half's
worst margin and how many scenes meet every target, for both.
"""
import json
import sys

from mi_voldis.bench.family import TARGET_CONSISTENCY, TARGET_IOU, TARGET_MARGIN, scene_row


def load(paths):
    merged = None
    for p in paths:
        with open(p) as f:
            r = json.load(f)
        if merged is None:
            merged = r
        else:
            merged["scenes"].update(r["scenes"])
    return merged


def meets(r):
    return (r["margin"] >= TARGET_MARGIN and r["consistency_margin"] is not None
            and r["consistency_margin"] >= TARGET_CONSISTENCY and (r["coverage_iou"] or 0) >= TARGET_IOU)


def fmt(r):
    if r is None:
        return "-"
    c = "-" if r["consistency_margin"] is None else f"{r['consistency_margin']:+.2f}"
    return (f"{r['margin']:+6.2f} {c:>6} {r['coverage_iou']:.2f} "
            f"{r['haze_mask']:.3f}/{r['haze_outside']:.3f}{' *' if meets(r) else '  '}")


def main():
    base, trial = load(sys.argv[1:2]), load(sys.argv[2:])
    print(f"base sets: {base.get('sets')}  trial sets: {trial.get('sets')}")
    print("columns: margin, consistency margin, coverage IoU, haze in hole/outside; * meets every target")
    for half in ("tuning", "check"):
        scenes = [s for s, e in trial["scenes"].items() if e["half"] == half]
        if not scenes:
            continue
        print(f"\n{half} half")
        worst = {"base": [], "trial": []}
        for s in sorted(scenes):
            b = scene_row(base["scenes"][s], "guided") if s in base["scenes"] else None
            t = scene_row(trial["scenes"][s], "guided")
            print(f"  {s:9s} {trial['scenes'][s]['kind']:9s} base {fmt(b):38s} trial {fmt(t)}")
            if b is not None:
                worst["base"].append((b["margin"], s, meets(b)))
            worst["trial"].append((t["margin"], s, meets(t)))
        for k, v in worst.items():
            if v:
                m = min(v)
                print(f"  {k}: worst {m[1]} {m[0]:+.2f} dB over {len(v)} scenes; "
                      f"{sum(x[2] for x in v)} meet every target")


if __name__ == "__main__":
    main()
