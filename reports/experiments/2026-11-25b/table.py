"""The shadow search on or off, per scene: a markdown table from pairs of strategies refits.

    python reports/experiments/2026-11-25b/table.py NAME=OFF_DIR,ON_DIR ...

OFF_DIR / ON_DIR: ``python -m mi_voldis.bench.strategies RUN guided DIR`` outputs, the first with
``--set shadow_contrast=0``, the second with the defaults.
"""
import json
import sys


def load(path):
    with open(f"{path}/metrics.json") as f:
        return json.load(f)


def fmt(x, digits=2):
    return "-" if x is None else f"{x:.{digits}f}"


def main(pairs):
    print("| scene | light kept (edge contrast, views agreeing, shading) | in mask, off / on | Telea / NS | "
          "margin over the best (target +2) | outside, off / on (full field) | coverage IoU, off / on | "
          "matte IoU, off / on | residue, off / on | refit seconds, off / on |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for pair in pairs:
        name, dirs = pair.split("=", 1)
        off, on = (load(d) for d in dirs.split(","))
        a, b = off["methods"]["volume"], on["methods"]["volume"]
        rec = (on.get("prior") or {}).get("shadow")
        light = "-" if rec is None else ("yes" if rec["kept"] else "no") + \
            f" ({rec['contrast']:.2f}, {rec['views_agree']:.2f}, {rec['shading']:.2f})"
        telea, ns = (on["methods"].get(k, {}).get("psnr_mask") for k in ("telea", "ns"))
        best = max(x for x in (telea, ns) if x is not None) if telea is not None else None
        margin = None if best is None or b["psnr_mask"] is None else b["psnr_mask"] - best
        print(f"| {name} | {light} | {fmt(a['psnr_mask'])} / {fmt(b['psnr_mask'])} | {fmt(telea)} / {fmt(ns)} | "
              f"{'-' if margin is None else f'{margin:+.2f}'} | {fmt(a['psnr_outside'])} / {fmt(b['psnr_outside'])} "
              f"({fmt(b['full_psnr_outside'])}) | {fmt(a['fg_coverage_iou'])} / {fmt(b['fg_coverage_iou'])} | "
              f"{fmt(a['fg_matte_iou'])} / {fmt(b['fg_matte_iou'])} | {fmt(a['residue'])} / {fmt(b['residue'])} | "
              f"{off['seconds']:.0f} / {on['seconds']:.0f} |")


if __name__ == "__main__":
    main(sys.argv[1:])
