"""How much each family scene's object changes the light on what lies around it, and whether the photos alone
show it: per scene, over the masked views, in the scored ring (the mask dilated by the scoring dilation, less the
mask):
- photo against the truth: PSNR, and the mean log-luminance step (photo / truth; < 0: the object darkens it);
- the step seen without the truth: photo against a 2D inpainting of the dilated mask from beyond it (FSR);
- in the scored mask: Telea's fill (sources beyond the dilation) and the photo kept in the ring with Telea on the
  object's own pixels (what a background that keeps what views see unmasked can reach at best).

    python ring2d.py DATA_ROOT SCENE...
"""
import os
import sys

import numpy as np

import mi_voldis  # noqa: F401
from mi_voldis.data import load_dataset
from mi_voldis.inpaint2d import inpainter
from mi_voldis.metrics import dilate, psnr, score_dilation

EPS = 1e-3


def lum(x):
    return np.log(np.clip(x[..., :3], 0, None) @ np.array([0.2126, 0.7152, 0.0722]) + EPS)


root, scenes = sys.argv[1], sys.argv[2:]
telea, fsr = inpainter("telea"), inpainter("auto")
for scene in scenes:
    ds = load_dataset(os.path.join(root, scene), "transforms", 8)
    dil = score_dilation(ds.size)
    rows = []
    for v in range(len(ds.images)):
        if not ds.masks[v].any():
            continue
        photo, gt = np.clip(ds.images[v][..., :3], 0, 1), np.clip(ds.backgrounds[v][..., :3], 0, 1)
        m = dilate(ds.masks[v], dil)
        ring = m & ~ds.masks[v]
        if ring.sum() < 20:
            continue
        fill = fsr(photo, m)
        tel = telea(photo, m)
        keep = np.where(ring[..., None], photo, tel)
        rows.append((psnr(photo, gt, ring), float(np.mean((lum(photo) - lum(gt))[ring])),
                     float(np.median((lum(photo) - lum(fill))[ring])), psnr(tel, gt, m), psnr(keep, gt, m)))
    r = np.array(rows)
    print(f"{scene}: views {len(r)}; ring photo/truth {np.median(r[:, 0]):.2f} dB, step {np.median(r[:, 1]):+.3f}; "
          f"step against FSR {np.median(r[:, 2]):+.3f} (views below -0.03: {np.mean(r[:, 2] < -0.03):.2f}); "
          f"in mask: Telea {np.median(r[:, 3]):.2f}, photo ring + Telea {np.median(r[:, 4]):.2f}", flush=True)
