"""Side by side, per family scene, two bench work folders' default (guided) rows and full fields.

    python reports/experiments/2026-11-27/split/compare.py OLD_WORK NEW_WORK [--json OUT]

Per scene: the full field's held-out PSNR, the background's in-mask PSNR and its margin over the better of
Telea and Navier-Stokes, view consistency, foreground coverage IoU, haze in the hole / outside; then per
half the worst margin and the mean change. Only scenes both folders have finished are compared.
"""
import argparse
import json
import os


def row(work, scene, strategy="guided"):
    path = os.path.join(work, "removal", scene, strategy, "metrics.json")
    run = os.path.join(work, "runs", f"{scene}_0", "metrics.json")
    if not (os.path.isfile(path) and os.path.isfile(run)):
        return None
    with open(path) as f:
        m = json.load(f)["methods"]
    with open(run) as f:
        fit = json.load(f)
    v = m["volume"]
    classic = max(m[n]["psnr_mask"] for n in ("telea", "ns") if n in m)
    return {"full": fit["held_out"]["psnr"], "grid": fit["grid"]["full"], "mask": v["psnr_mask"],
            "margin": v["psnr_mask"] - classic, "consistency": v["consistency_psnr"],
            "iou": v.get("fg_coverage_iou"), "haze_in": v.get("bg_haze_mask"), "haze_out": v.get("bg_haze_outside"),
            "fit_s": fit["seconds"]["fit"]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--json")
    a = ap.parse_args()
    out = {}
    print("scene    | full old/new | in-mask old/new | margin old/new | consist. old/new | IoU old/new | haze in/out")
    for k in range(20):
        scene = f"family{k:02d}"
        o, n = row(a.old, scene), row(a.new, scene)
        if o is None or n is None:
            continue
        out[scene] = {"old": o, "new": n}
        print(f"{scene} | {o['full']:.2f} {n['full']:.2f} | {o['mask']:.2f} {n['mask']:.2f} | "
              f"{o['margin']:+.2f} {n['margin']:+.2f} | {o['consistency']:.2f} {n['consistency']:.2f} | "
              f"{o['iou']:.3f} {n['iou']:.3f} | {n['haze_in']:.3f} {n['haze_out']:.3f}")
    for half, ks in (("tuning", range(10)), ("check", range(10, 20))):
        rows = [out[f"family{k:02d}"] for k in ks if f"family{k:02d}" in out]
        if not rows:
            continue
        worst = {w: min(r[w]["margin"] for r in rows) for w in ("old", "new")}
        mean = {key: sum(r["new"][key] - r["old"][key] for r in rows) / len(rows)
                for key in ("full", "mask", "margin", "consistency", "iou")}
        print(f"{half} ({len(rows)} scenes): worst margin {worst['old']:+.2f} -> {worst['new']:+.2f}; mean change "
              + ", ".join(f"{key} {v:+.3f}" for key, v in mean.items()))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
