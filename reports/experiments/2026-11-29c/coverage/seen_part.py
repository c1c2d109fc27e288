"""#46: the background against its own 2D prior (FSR), split into the part of the hole some training view sees
and the part none sees, per held-out view, with a sheet of crops around the mask.

    python reports/experiments/2026-11-29c/coverage/seen_part.py RUN OUT.png   # RUN fitted with --keep-checkpoints

Per view: PSNR of the volume's background and of FSR on the same view against the true background, in the seen
and the unseen part of the scored region (the mask dilated as mi_voldis.bench.strategies scores it; "seen" as it
counts it). Sheet rows: held-out views; columns: photo, true background, volume, FSR, |volume - truth| x 4,
|FSR - truth| x 4, the region (grey) and its seen part (white). OUT.png must not exist.
"""
import json
import os
import sys

import numpy as np
from PIL import Image

import mi_voldis  # noqa: F401  (sets the variant)
from mi_voldis.bench.strategies import refit_config
from mi_voldis.bench.visible import seen_pixels, training_surfaces
from mi_voldis.data import load_dataset
from mi_voldis.fit.fields import FitInputs, fit_integrator
from mi_voldis.fit.state import FitState
from mi_voldis.inpaint2d import inpainter
from mi_voldis.io.images import display_to_uint8
from mi_voldis.metrics import dilate, psnr, score_dilation
from mi_voldis.optim.adam import Adam
from mi_voldis.render.views import render_camera

run, out = sys.argv[1], sys.argv[2]
if os.path.lexists(out):
    sys.exit(f"error: {out} exists; give a new file")
ckpt = os.path.join(run, "checkpoints", "last.npz")
cfg = refit_config(run, "guided")
rec = json.load(open(os.path.join(run, "config.json")))["dataset"]
ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
state = FitState.load(ckpt, Adam({}, 0.9, 0.99))
inputs = FitInputs.of(ds, cfg, "/tmp/none.npz", progress=False)
integ = fit_integrator(inputs, state)
dil = score_dilation(ds.size)
surf = training_surfaces(ds, integ)
rows = []
for v in ds.test:
    r = render_camera(integ, ds.cameras[v], ("full", "bg", "fg"))
    region, gt = dilate(ds.masks[v], dil), ds.backgrounds[v]
    seen = seen_pixels(ds, v, region, r["bg"][2], surf)
    vol = np.clip(r["bg"][0], 0, 1)
    fsr = inpainter("fsr")(ds.images[v], region)
    print(v, "volume seen / unseen %.2f / %.2f" % (psnr(vol, gt, seen), psnr(vol, gt, region & ~seen)),
          "FSR %.2f / %.2f" % (psnr(fsr, gt, seen), psnr(fsr, gt, region & ~seen)))
    ys, xs = np.nonzero(region)
    y0, y1, x0, x1 = max(ys.min() - 6, 0), ys.max() + 7, max(xs.min() - 6, 0), xs.max() + 7
    def c(a):
        return a[y0:y1, x0:x1]
    seenimg = np.stack([region * 0.4 + seen * 0.6] * 3, -1)
    panel = [c(ds.images[v][..., :3]), c(gt), c(vol), c(fsr), np.clip(4 * np.abs(c(vol) - c(gt)), 0, 1),
             np.clip(4 * np.abs(c(fsr) - c(gt)), 0, 1), c(seenimg)]
    rows.append(np.concatenate([display_to_uint8(p) if k < 4 else (p * 255).astype(np.uint8)
                                for k, p in enumerate(panel)], 1))
w = max(r.shape[1] for r in rows)
im = np.concatenate([np.pad(r, ((0, 2), (0, w - r.shape[1]), (0, 0))) for r in rows], 0)
Image.fromarray(im).resize((im.shape[1] * 3, im.shape[0] * 3), Image.NEAREST).save(out)
