"""#46: the photos over the true background (linear) on the ring around each masked training view's mask, binned by the
object's ambient occlusion o(x) (occ.py) of the full field's surface there: does 1 - gamma o explain the darkening?
    python reports/experiments/2026-11-29/occlusion/diag.py FITS/runs/familyNN_0 FITS/data/familyNN"""
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
# the imports below come after set_variant on purpose
import imageio.v3 as iio  # noqa: E402
from occ import object_grid, occlusion  # noqa: E402

from mi_voldis.bench.strategies import refit_config  # noqa: E402
from mi_voldis.data import load_dataset  # noqa: E402
from mi_voldis.fit.fields import FitInputs  # noqa: E402
from mi_voldis.fit.hull import visual_hull  # noqa: E402
from mi_voldis.fit.lift import training_depths  # noqa: E402
from mi_voldis.fit.shadow import ObjectSurface, surface_points  # noqa: E402
from mi_voldis.fit.state import FitState  # noqa: E402
from mi_voldis.io.images import srgb_to_linear  # noqa: E402
from mi_voldis.metrics import dilate  # noqa: E402
from mi_voldis.optim.adam import Adam  # noqa: E402

run = sys.argv[1]
data = sys.argv[2]
cfg = refit_config(run, "guided", [])
rec = json.load(open(f"{run}/config.json"))["dataset"]
ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
state = FitState.load(f"{run}/checkpoints/last.npz", Adam({}, 0.9, 0.99))
inputs = FitInputs.of(ds, cfg.for_backend("llvm"), os.path.join(run, "unused.npz"), False)
t = time.time()
depth = training_depths(inputs, state, count=len(ds.train), median=True)
masked = [v for v in ds.masked_train if v in depth]
cams, masks, depths = [ds.cameras[v] for v in masked], [ds.masks[v] for v in masked], [depth[v] for v in masked]
surf = ObjectSurface.of(cams, [ds.images[v] for v in masked], masks, depths)
grow = int(np.ceil(cfg.hull_dilation * np.hypot(*ds.size)))
surf = surf.inside(visual_hull(surf.points, cams, masks, grow, cfg.hull_min_views, depths))
pts = surf.points
radius = surf.spacing / np.sqrt(2)
print("depths+surface", time.time() - t, len(pts), "spacing", surf.spacing)
grid = object_grid(pts, max(radius, 0), 64)
print("grid", grid[0].shape, grid[0].mean(), "voxel", grid[2])
diag = np.hypot(*ds.size)
res = []
for v, cam, m, dep in zip(masked, cams, masks, depths):
    h, w = m.shape
    ys, xs = np.mgrid[0:h, 0:w]
    p, n = surface_points(cam, dep, xs, ys)
    ring = (dilate(m, int(np.ceil(0.10 * diag))) & ~dilate(m, 1)).reshape(-1)
    t = time.time()
    o = np.full(h * w, np.nan)
    o[ring] = occlusion(grid, p[ring], n[ring])
    truth = iio.imread(f"{data}/backgrounds/view_{v:03d}.png")[..., :3] / 255.0
    photo = ds.images[v]
    # photo over true background in linear RGB (background floored at 1e-3)
    ratio = srgb_to_linear(np.clip(photo, 0, 1)).reshape(-1, 3) / np.maximum(srgb_to_linear(truth).reshape(-1, 3), 1e-3)
    res.append((o, ratio, ring, m, v))

print("occl per view s", time.time() - t)
# pool the ring pixels of all views: occlusion o and photo/truth ratio
occl = np.concatenate([r[0][r[2]] for r in res])
rat = np.concatenate([r[1][r[2]] for r in res])
ok = np.isfinite(occl) & np.all(rat > 0.05, 1)
occl, rat = occl[ok], rat[ok]
for lo_, hi_ in [(0, .01), (.01, .05), (.05, .1), (.1, .2), (.2, .3), (.3, .5), (.5, 1.01)]:
    s = (occl >= lo_) & (occl < hi_)
    if s.sum():
        print(
            f"o in [{lo_},{hi_}): n={s.sum():6d} median photo/truth (lin) {np.round(np.median(rat[s], 0), 3)}"
            f"  1-o_mean={1 - occl[s].mean():.3f}"
        )
