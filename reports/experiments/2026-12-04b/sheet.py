"""Rows: held-out views; columns: photo, truth bg, Telea, volume bg, plate, |plate-truth|x4 (crop around the mask)."""
import sys, os, json
import numpy as np, imageio.v3 as iio
from mi_voldis.data import load_dataset
from mi_voldis.inpaint2d import inpainter
from mi_voldis.compositing import clean_plate
from mi_voldis.metrics import dilate, score_dilation
from mi_voldis.io.images import write_png, display_to_uint8
out_dir, data, dest = sys.argv[1:4]
ds = load_dataset(data)
dil = score_dilation(ds.size)
rows = []
for v in ds.test:
    f = os.path.join(out_dir, f"view{v:03d}_bg.png")
    if not os.path.exists(f):
        continue
    bg = iio.imread(f)[..., :3].astype(np.float32) / 255
    hole = dilate(ds.masks[v], dil)
    plate = clean_plate(bg, ds.images[v], hole)[1]
    t = inpainter("telea")(ds.images[v], hole)
    ys, xs = np.nonzero(hole); y0, y1 = max(ys.min()-20,0), ys.max()+20; x0, x1 = max(xs.min()-20,0), xs.max()+20
    err = np.clip(4*np.abs(plate - ds.backgrounds[v]), 0, 1)
    row = [ds.images[v], ds.backgrounds[v], t, bg, plate, err]
    rows.append(np.concatenate([r[y0:y1, x0:x1] for r in row], 1))
w = max(r.shape[1] for r in rows)
rows = [np.pad(r, ((0, 4), (0, w - r.shape[1]), (0, 0))) for r in rows]
write_png(dest, display_to_uint8(np.concatenate(rows, 0)))
