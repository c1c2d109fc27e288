"""#46/#42 probe: how many training views frame each vertex of a run's full field, and the held-out PSNR of
the full field when vertices framed by fewer than K training views are emptied (density -> empty).

    python cull.py RUN OUT K...      # OUT: a new folder; writes OUT/K<k>/ run copies and prints a table
"""
import os
import shutil
import sys

import numpy as np

sys.path.insert(0, os.getcwd())
# mi_voldis first: it points Dr.Jit at a libLLVM that works before Mitsuba loads
import mi_voldis  # noqa: E402, I001
import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
from PIL import Image  # noqa: E402
from mi_voldis.bricks import EMPTY_DENSITY, Layout  # noqa: E402
from mi_voldis.cameras import DevicePoints  # noqa: E402

if len(sys.argv) < 4 or not all(k.isdigit() for k in sys.argv[3:]):
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
run, out, ks = sys.argv[1], sys.argv[2], [int(k) for k in sys.argv[3:]]
if not os.path.isfile(os.path.join(run, "full_grid.npz")):
    raise SystemExit(f"cull.py: {run}: not a run folder (no full_grid.npz)")
if os.path.lexists(out):
    raise SystemExit(f"cull.py: {out} exists; give a new folder")
if os.path.realpath(out).startswith(os.path.realpath(run) + os.sep):
    raise SystemExit(f"cull.py: {out} lies inside the run {run}; give a folder outside it")
os.makedirs(out)
r = mi_voldis.load_run(run)
ds = r.dataset
z = dict(np.load(os.path.join(run, "full_grid.npz")))
lay = Layout(tuple(z["vertices"]), int(z["brick"]), z["table"])
coords, inside = lay.vertex_coords()
if len(coords) == len(z["data"]) + lay.vertices_per_brick:  # the file leaves out the empty slot
    coords, inside = coords[lay.vertices_per_brick:], inside[lay.vertices_per_brick:]
lo, hi = z["bbox"]
pts = lo + coords / (np.array(lay.shape) - 1) * (hi - lo)
at = DevicePoints(np.where(inside[:, None], pts, 0.0))
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


def score(path, label):
    rr = mi_voldis.load_run(path)
    line = []
    for v in ds.test:
        full = np.clip(rr.render(view=int(v), layers=("full",), linear=False)["full"][..., :3], 0, 1)
        line.append(f"v{int(v)} {-10 * np.log10(((full - ds.images[int(v)]) ** 2).mean()):.2f}")
        Image.fromarray((full * 255 + 0.5).astype(np.uint8)).save(os.path.join(out, f"{label}_v{int(v):03d}.png"))
    print(f"{label}: " + "  ".join(line), flush=True)


score(run, "fit")
for k in ks:
    d = os.path.join(out, f"K{k}")
    os.makedirs(d)
    for f in os.listdir(run):
        if f not in ("full_grid.npz", "checkpoints", "previews"):
            src = os.path.join(run, f)
            (shutil.copytree if os.path.isdir(src) else shutil.copy2)(src, os.path.join(d, f))
    zz = dict(z)
    data = z["data"].copy()
    kill = inside & (count < k)
    data[kill, 0] = EMPTY_DENSITY
    zz["data"] = data
    np.savez(os.path.join(d, "full_grid.npz"), **zz)
    print(f"K={k}: emptied {(kill & sel).sum()} dense vertices")
    score(d, f"K{k}")
np.save(os.path.join(out, "count.npy"), count)
