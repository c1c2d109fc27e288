"""#46/#42 probe: how many training views frame each vertex of a run's full field, and the held-out PSNR of
the full field when vertices framed by fewer than K training views are emptied (density -> empty).

    python cull.py RUN OUT K...      # OUT: a new folder; writes OUT/K<k>/ run copies and prints a table
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.getcwd())
# mi_voldis first: it points Dr.Jit at a libLLVM that works before Mitsuba loads
import mi_voldis  # noqa: E402, I001
import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
from mi_voldis.cameras import DevicePoints  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-12-02g"))
from grid_probe import check_paths, emptied_copy, grid_vertices, score  # noqa: E402  (shared with later probes)

if len(sys.argv) < 4 or not all(k.isdigit() for k in sys.argv[3:]):
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
run, out, ks = sys.argv[1], sys.argv[2], [int(k) for k in sys.argv[3:]]
check_paths("cull.py", run, out)
os.makedirs(out)
r = mi_voldis.load_run(run)
ds = r.dataset
z, inside, pts = grid_vertices(run)
at = DevicePoints(pts)
count = dr.zeros(mi.UInt32, at.count)
for v in ds.train:
    _, ok = at.pixel_of(ds.cameras[int(v)])
    count += dr.select(ok, 1, 0)
    dr.eval(count)
count = count.numpy()
dens = z["data"][:, 0]
sel = inside & (dens > -5)
print(f"{run}: {inside.sum()} vertices, {sel.sum()} with raw density > -5; training views {len(ds.train)}")
for k in range(0, 6):
    print(f"  framed by {k} views: {(sel & (count == k)).sum()}")

score(run, ds, out, "fit")
for k in ks:
    kill = inside & (count < k)
    emptied_copy(run, z, kill, os.path.join(out, f"K{k}"))
    print(f"K={k}: emptied {(kill & sel).sum()} dense vertices")
    score(os.path.join(out, f"K{k}"), ds, out, f"K{k}")
np.save(os.path.join(out, "count.npy"), count)
