"""The default (guided) removal row of family scenes before and after a change: the bench's rows in
OLD_WORK/removal/SCENE/guided against NEW/SCENE (refits by mi_voldis.bench.strategies).

    [ROWS_JSON=OUT.json] python reports/experiments/2026-11-27/shadow/rows.py OLD_WORK NEW SCENE [SCENE ...]
"""
import json
import os
import sys


def row(path):
    with open(os.path.join(path, "metrics.json")) as f:
        d = json.load(f)
    m, v = d["methods"], d["methods"]["volume"]
    classic = max(m[n]["psnr_mask"] for n in ("telea", "ns") if n in m)
    best_c = max(m[n]["consistency_psnr"] for n in m if n != "volume")
    shadow = (d.get("prior") or {}).get("shadow") or {}
    return {"psnr_mask": v["psnr_mask"], "margin": v["psnr_mask"] - classic, "consistency": v["consistency_psnr"],
            "consistency_margin": v["consistency_psnr"] - best_c, "iou": v.get("fg_coverage_iou"),
            "haze_in": v.get("bg_haze_mask"), "haze_out": v.get("bg_haze_outside"), "residue": v["residue"],
            "shadow_kept": shadow.get("kept")}


if __name__ == "__main__":
    old, new, scenes = sys.argv[1], sys.argv[2], sys.argv[3:]
    out = {s: {"old": row(os.path.join(old, "removal", s, "guided")), "new": row(os.path.join(new, s))}
           for s in scenes if os.path.isfile(os.path.join(new, s, "metrics.json"))}
    for s, r in out.items():
        o, n = r["old"], r["new"]
        print(f"{s}: shadow kept {o['shadow_kept']} -> {n['shadow_kept']}; in-mask {o['psnr_mask']:.2f} -> "
              f"{n['psnr_mask']:.2f} (margin {o['margin']:+.2f} -> {n['margin']:+.2f}); consistency margin "
              f"{o['consistency_margin']:+.2f} -> {n['consistency_margin']:+.2f}; "
              f"IoU {o['iou']:.3f} -> {n['iou']:.3f}; "
              f"haze in/out {n['haze_in']:.3f}/{n['haze_out']:.3f}; residue {o['residue']:.3f} -> {n['residue']:.3f}")
    if os.environ.get("ROWS_JSON"):
        with open(os.environ["ROWS_JSON"], "w") as f:
            json.dump(out, f, indent=1)
