"""The lateral fill against Telea, NS and FSR as 2D inpainters on the removal family's held-out views: in-mask
PSNR against the true background (masks dilated as the removal bench scores them), per scene.

    python score2d.py FAMILY_DATA SCENE...
"""
# ruff: noqa: E402
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from lateral import lateral_inpaint, select_inpainter

from mi_voldis.data import load_dataset
from mi_voldis.inpaint2d import inpainter
from mi_voldis.metrics import dilate, psnr, score_dilation

root = sys.argv[1]
methods = {"telea": inpainter("telea"), "ns": inpainter("ns"), "fsr": inpainter("fsr"),
           "lateral": lateral_inpaint, "lateral_s2": lambda i, m: lateral_inpaint(i, m, smooth=2)}
pair = {"fsr": methods["fsr"], "lateral_s2": methods["lateral_s2"]}


def selected(image, hole):
    name = select_inpainter(image, hole, pair) or "fsr"
    picks.append(name)
    return pair[name](image, hole)


methods["select"] = selected
from mi_voldis.inpaint2d import lateral_inpaint as package_lateral  # noqa: E402

methods["package"] = package_lateral
from lateral import oriented_inpaint  # noqa: E402

methods["oriented"] = oriented_inpaint
methods["oriented_c3"] = lambda i, m: oriented_inpaint(i, m, 0.3)
methods["mean"] = lambda i, m: 0.5 * (pair["fsr"](i, m) + pair["lateral_s2"](i, m))
print("scene | " + " | ".join(methods) + " | lateral - max(telea, ns)")
for scene in sys.argv[2:]:
    ds = load_dataset(os.path.join(root, scene), "transforms", 8)
    dil = score_dilation(ds.size)
    score = {k: [] for k in methods}
    picks = []
    for v in ds.test:
        region = dilate(ds.masks[v], dil)
        for k, f in methods.items():
            score[k].append(psnr(f(ds.images[v][..., :3], region), ds.backgrounds[v], region))
    s = {k: float(np.mean(x)) for k, x in score.items()}
    print(scene, "|", " | ".join(f"{s[k]:.2f}" for k in methods),
          f"| {s['lateral'] - max(s['telea'], s['ns']):+.2f}", picks)
