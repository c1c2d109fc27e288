"""Points along rays of view 8 through the statue's mask: in front of / far behind / behind the hidden
surface, and seen unmasked.
"""

import sys

import numpy as np
from kept_run import open_run

import mi_voldis  # noqa
from mi_voldis.bench.strategies import refit_config
from mi_voldis.cameras import pixel_rays
from mi_voldis.fit.lift import training_depths
from mi_voldis.fit.visibility import hidden_surface_side, in_view
from mi_voldis.inpaint2d import fill_disparity
from mi_voldis.metrics import dilate

run = sys.argv[1]
cfg, ds, state, inputs = open_run(run, refit_config(run, "guided"))
depth = training_depths(inputs, state, median=True)
views = [u for u in depth if u in set(int(x) for x in ds.masked_train)]
diag = np.hypot(*ds.size)
grow = int(np.ceil(0.01 * diag))
cam = ds.cameras[8]
for py_, px_ in [(119, 282), (172, 281), (207, 275)]:
    o, d = pixel_rays(cam, np.array([px_ + 0.5]), np.array([py_ + 0.5]))
    ts = np.array([40, 50, 60, 70, 80, 90, 100, 110, 120, 130, 140, 160, 200])
    pts = o + ts[:, None] * d
    fr, far, bey = hidden_surface_side(
        pts, [ds.cameras[u] for u in views], [depth[u] for u in views], [ds.masks[u] for u in views], grow, 0.05, 0.25
    )
    seen = in_view(
        pts,
        [ds.cameras[u] for u in views],
        [depth[u] for u in views],
        [dilate(ds.masks[u], 1) for u in views],
        tol=0.05,
    )
    print((py_, px_), "t", ts.tolist())
    for name, x in (("front", fr), ("far", far), ("beyond", bey), ("seen", seen)):
        print("  %-6s" % name, x.astype(int).tolist())
# filled depth of a training view near view 8, at its mask center
u = views[len(views) // 2]
hole = dilate(ds.masks[u], grow)
known = np.isfinite(depth[u]) & ~hole
f = fill_disparity(np.where(known, depth[u], np.nan), hole, known, camera=ds.cameras[u])
ys, xs = np.nonzero(ds.masks[u])
print(
    "view",
    u,
    "filled depth in mask percentiles",
    np.percentile(f[ys, xs], [5, 25, 50, 75, 95]).round(1),
    "ring depth pct",
    np.nanpercentile(np.where(dilate(hole, 8) & known, depth[u], np.nan), [5, 50, 95]).round(1),
)
