"""#46/#42 probe: the full field with the fog in free space emptied. A vertex is culled when fewer than K
training views frame it and every view that frames it sees it in front of its surface: nearer than MARGIN
times the expected depth (sum w t / sum w) that view's full-field render has at the vertex's pixel. Space
carving by what the views see through: the surfaces those few views end on are kept, the haze before them
goes. Scores the held-out views' full field against the photos.

    python cull_free.py RUN OUT MARGIN K...   # OUT: a new folder; writes OUT/K<k>/ run copies, prints a table
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
from mi_voldis.cameras import DevicePoints, device_image  # noqa: E402

args = sys.argv[1:]
if len(args) < 4 or not all(k.isdigit() for k in args[3:]):
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
run, out, ks = args[0], args[1], [int(k) for k in args[3:]]
try:
    margin = float(args[2])
except ValueError:
    raise SystemExit(f"cull_free.py: MARGIN {args[2]!r} is not a number") from None
if not os.path.isfile(os.path.join(run, "full_grid.npz")):
    raise SystemExit(f"cull_free.py: {run}: not a run folder (no full_grid.npz)")
if os.path.lexists(out):
    raise SystemExit(f"cull_free.py: {out} exists; give a new folder")
if os.path.realpath(out).startswith(os.path.realpath(run) + os.sep):
    raise SystemExit(f"cull_free.py: {out} lies inside the run {run}; give a folder outside it")
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
    kill = inside & (count >= 1) & (count < k) & front
    data[kill, 0] = EMPTY_DENSITY
    zz["data"] = data
    np.savez(os.path.join(d, "full_grid.npz"), **zz)
    print(f"K={k}: emptied {(kill & sel).sum()} dense vertices")
    score(d, f"K{k}")
