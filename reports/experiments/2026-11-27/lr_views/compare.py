"""The lr_views screen (run.sh) as JSON: per removal-family scene, the committed default's fit and each
variant's, on the fit's own held-out metrics (full field, background in the dilated mask, coverage IoU,
haze) and per held-out view; with the tuning / check half of each scene.

    python reports/experiments/2026-11-27/lr_views/compare.py p1 [NAME ...] > results.json
"""
import json
import os
import sys

KEYS = ("psnr", "bg_psnr_mask", "fg_coverage_iou", "bg_haze_mask", "bg_haze_outside")


def summary(path):
    with open(path) as f:
        m = json.load(f)
    return {"run": os.path.dirname(path), **{k: m["held_out"][k] for k in KEYS},
            "views": [{k: r[k] for k in ("view", "psnr", "fg_coverage_iou")} for r in m["per_view"]],
            "fit_seconds": m["seconds"]["fit"], "grid": m["grid"]["full"] if isinstance(m["grid"], dict) else m["grid"]}


def main(names):
    out = {}
    for k in range(20):
        scene = f"family{k:02d}"
        runs = {n: f"out/lrv/{scene}_{n}/metrics.json" for n in names}
        runs = {n: p for n, p in runs.items() if os.path.exists(p)}
        if not runs:
            continue
        row = {"half": "tuning" if k < 10 else "check",
               "default": summary(f"out/fam_split/runs/{scene}_0/metrics.json")}
        for n, p in runs.items():
            row[n] = summary(p)
            row[n]["change"] = {key: row[n][key] - row["default"][key] for key in KEYS}
        out[scene] = row
    json.dump(out, sys.stdout, indent=1)


if __name__ == "__main__":
    main(sys.argv[1:])
