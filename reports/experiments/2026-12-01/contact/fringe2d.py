"""The dark fringe beside a mask, in 2D: per family scene, over the masked views, the pixels within 1% of the
diagonal outside the mask (the band the colour prior already inpaints) that are darker in every channel than the
prior's 2D fill (FSR from beyond the band) by at least T in log; against the truth: what share of the band they
are, their log step against the truth (the object's contact shadow or dark edge: < 0), and the scored ring's
PSNR (the mask dilated as scored, less the mask) with the photo kept there against the flagged pixels replaced by
the fill.

    python fringe2d.py DATA_ROOT T SCENE...
"""
import os
import sys

import numpy as np

import mi_voldis  # noqa: F401
from mi_voldis.data import load_dataset
from mi_voldis.inpaint2d import inpainter
from mi_voldis.metrics import dilate, psnr, score_dilation

EPS = 1e-3
root, T, scenes = sys.argv[1], float(sys.argv[2]), sys.argv[3:]
BAND = float(os.environ.get("BAND", "0.01"))  # the band, fraction of the diagonal
fsr = inpainter(os.environ.get("FILL", "auto"))  # the fill the fringe is judged against
for scene in scenes:
    ds = load_dataset(os.path.join(root, scene), "transforms", 8)
    dil, band_px = score_dilation(ds.size), int(np.ceil(BAND * np.hypot(*ds.size)))
    share, step_in, step_out, kept, mended, n = [], [], [], [], [], 0
    for v in range(len(ds.images)):
        m = ds.masks[v]
        if not m.any():
            continue
        photo, gt = np.clip(ds.images[v][..., :3], 0, 1), np.clip(ds.backgrounds[v][..., :3], 0, 1)
        hole = dilate(m, band_px)
        band = hole & ~m
        fill = fsr(photo, hole)
        darker = np.all(np.log(photo + EPS) - np.log(fill + EPS) < -T, axis=-1) & band
        if os.environ.get("LOCALMIN"):  # and darker than every known pixel near it, in every channel
            import cv2
            r = 2 * band_px
            known = np.where(hole[..., None], 2.0, photo).astype(np.float32)
            low = cv2.erode(known, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)))
            darker &= np.all(photo < low, axis=-1)
        if os.environ.get("ATTACHED"):  # only the parts that touch the mask
            import cv2
            n, labels = cv2.connectedComponents(darker.astype(np.uint8), connectivity=8)
            touching = np.unique(labels[dilate(m, 1) & darker])
            darker = np.isin(labels, touching[touching > 0])
        truth_step = np.mean(np.log(photo + EPS) - np.log(gt + EPS), axis=-1)
        share.append(darker.sum() / max(band.sum(), 1))
        if darker.any():
            step_in.append(truth_step[darker].mean())
        step_out.append(truth_step[band & ~darker].mean())
        ring = dilate(m, dil) & ~m
        mend = np.where(darker[..., None], fill, photo)
        kept.append(psnr(photo, gt, ring))
        mended.append(psnr(mend, gt, ring))
        n += 1
    print(f"{scene}: views {n}, flagged {100 * np.mean(share):.1f}% of the band; log step against the truth: flagged "
          f"{np.mean(step_in) if step_in else float('nan'):+.3f}, the rest {np.mean(step_out):+.3f}; scored ring "
          f"photo {np.median(kept):.2f} -> mended {np.median(mended):.2f} dB", flush=True)
