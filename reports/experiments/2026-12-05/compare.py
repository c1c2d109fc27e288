"""The capture bench's default fits under each `strides` value, side by side, from their run folders.

    python reports/experiments/2026-12-05/compare.py LABEL=WORK [LABEL=WORK ...] > compare.txt

WORK: a `scripts/bench.py --work` folder (its fits in WORK/runs/NAME_0). Per capture and label: held-out PSNR
and per view, the final grid, the bricks the last carve kept, samples a ray in the last 500 training steps and as
the written scene renders, the fit's seconds and the peak RSS. Plans are costed at the reference speed, so the
grids and steps do not depend on the machine's load; the seconds do (the benches ran alone)."""
import json
import os
import sys

import numpy as np

CAPTURES = ("fern", "horns", "statue", "garden")


def row(run):
    with open(os.path.join(run, "metrics.json")) as f:
        m = json.load(f)
    with open(os.path.join(run, "log.json")) as f:
        log = [e for e in json.load(f) if "samples" in e and str(e.get("phase", "")).startswith("full")]
    last = log[-500:]
    return {"psnr": m["held_out"]["psnr"], "views": [v["psnr"] for v in m["per_view"]],
            "grid": m["grid"]["full"][0], "bricks": m["bricks"]["full"]["allocated"],
            "of": m["bricks"]["full"]["of"], "steps": m["schedule"]["steps_full"],
            "step_samples": float(np.mean([e["samples"] for e in last])),
            "step_seconds": float(np.mean([e["step_seconds"] for e in last])),
            "train_spr": m["train_samples_per_ray"], "eval_spr": m["evaluated_samples_per_ray"],
            "fit": m["seconds"]["fit"], "rss": m["peak_rss_mib"]}


def main(pairs):
    works = [p.split("=", 1) for p in pairs]
    print("| capture | strides | held out dB | per view | final grid | bricks kept | steps | last 500 steps: "
          "M samples, s | samples a ray: training, scene | fit s | peak RSS MiB |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in CAPTURES:
        for label, work in works:
            run = os.path.join(work, "runs", f"{name}_0")
            if not os.path.exists(os.path.join(run, "metrics.json")):
                continue
            r = row(run)
            views = " / ".join(f"{v:.2f}" for v in r["views"][:4]) + (" ..." if len(r["views"]) > 4 else "")
            print(f"| {name} | {label} | {r['psnr']:.3f} | {views} | {r['grid']}^3 | {r['bricks']} of {r['of']} | "
                  f"{r['steps']} | {r['step_samples'] / 1e6:.2f}, {r['step_seconds']:.3f} | {r['train_spr']:.1f}, "
                  f"{r['eval_spr']:.1f} | {r['fit']:.0f} | {r['rss']:.0f} |")


if __name__ == "__main__":
    main(sys.argv[1:])
