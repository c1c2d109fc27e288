"""#46/#42 probe: the full field with the fog in free space emptied. A vertex is culled when fewer than K
training views frame it and every view that frames it sees it in front of its surface: nearer than MARGIN
times the expected depth (sum w t / sum w) that view's full-field render has at the vertex's pixel. Space
carving by what the views see through: the surfaces those few views end on are kept, the haze before them
goes. Scores the held-out views' full field against the photos.

    python cull_free.py RUN OUT MARGIN K...   # OUT: a new folder; writes OUT/K<k>/ run copies, prints a table
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.getcwd())
# mi_voldis first: it points Dr.Jit at a libLLVM that works before Mitsuba loads
import mi_voldis  # noqa: E402, I001
import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
from mi_voldis.cameras import DevicePoints, device_image  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from grid_probe import check_paths, emptied_copy, grid_vertices, score  # noqa: E402

args = sys.argv[1:]
if len(args) < 4 or not all(k.isdigit() for k in args[3:]):
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
run, out, ks = args[0], args[1], [int(k) for k in args[3:]]
try:
    margin = float(args[2])
except ValueError:
    raise SystemExit(f"cull_free.py: MARGIN {args[2]!r} is not a number") from None
check_paths("cull_free.py", run, out)
os.makedirs(out)
r = mi_voldis.load_run(run)
ds = r.dataset
z, inside, pts = grid_vertices(run)
at = DevicePoints(pts)
count = dr.zeros(mi.UInt32, at.count)
front = dr.full(mi.Bool, True, at.count)  # in front of the surface in every view that frames it
for v in ds.train:
    cam = ds.cameras[int(v)]
    depth = np.nan_to_num(r.render(view=int(v), layers=("full",))["depth"], nan=np.inf, posinf=np.inf)
    pix, ok = at.pixel_of(cam)
    d = dr.gather(mi.Float64, device_image(depth, mi.Float64), pix, ok)
    count += dr.select(ok, 1, 0)
    front &= ~ok | (at.distance(cam) < margin * d)
    dr.eval(count, front)
count, front = count.numpy(), front.numpy()
dens = z["data"][:, 0]
sel = inside & (dens > -5)
print(f"{run}: {inside.sum()} vertices, {sel.sum()} with raw density > -5; training views {len(ds.train)}; "
      f"margin {margin}")
score(run, ds, out, "fit")
for k in ks:
    kill = inside & (count >= 1) & (count < k) & front
    emptied_copy(run, z, kill, os.path.join(out, f"K{k}"))
    print(f"K={k}: emptied {(kill & sel).sum()} dense vertices")
    score(os.path.join(out, f"K{k}"), ds, out, f"K{k}")
