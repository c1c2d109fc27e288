"""Clean-plate variants on a run's held-out views, scored in the dilated mask against the true background:
layer, plate (bg matched to the photo), delta (bg + harmonic(photo - full) inside; photo + bg - full outside)."""
import sys, json
import numpy as np
from mi_voldis.tasks.base import FittedRun
from mi_voldis.render.views import render_camera
from mi_voldis.inpaint2d import membrane_inpaint, inpainter
from mi_voldis.metrics import dilate, score_dilation, psnr
out = {}
for run_dir in sys.argv[1:]:
    run = FittedRun(run_dir)
    ds, integ = run.dataset, run.integrator()
    dil = score_dilation(ds.size)
    rows = {k: [] for k in ("layer", "plate", "delta", "telea", "ns")}
    for v in ds.test:
        r = render_camera(integ, ds.cameras[v], ("full", "bg"))
        full, bg = np.clip(r["full"][0], 0, 1), np.clip(r["bg"][0], 0, 1)
        hole = dilate(ds.masks[v], dil)
        photo, gt = ds.images[v], ds.backgrounds[v]
        plate = bg + membrane_inpaint(photo - bg, hole)
        delta = bg + membrane_inpaint(photo - full, hole)
        for k, img in (("layer", bg), ("plate", plate), ("delta", delta),
                       ("telea", inpainter("telea")(photo, hole)), ("ns", inpainter("ns")(photo, hole))):
            rows[k].append(psnr(np.clip(img, 0, 1), gt, hole))
    m = {k: float(np.mean(x)) for k, x in rows.items()}
    c = max(m["telea"], m["ns"])
    name = run_dir.rstrip("/").split("/")[-1]
    out[name] = m
    print(name, " ".join(f"{k} {m[k]:.2f} ({m[k]-c:+.2f})" for k in ("layer", "plate", "delta")), f"classic {c:.2f}", flush=True)
json.dump(out, open("/work/runs/s45/variants.json", "a"))
