"""#46 probe: which training views hold the fog a held-out view sees just in front of itself. The full field's
vertices within DIST (world units) of held-out view VIEW's camera, in its frame and dense (raw density > -2),
are counted by how many training views frame them, and placed against each framing view's expected depth
(distance / depth: 1 on that view's surface, < 1 in front of it, > 1 hidden behind it). Training views that
frame at least 100 of them are written to OUT as rows: photo, fit, depth, the fog's pixels in red.

    python fog_views.py RUN VIEW DIST OUT      # OUT: a new folder
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.getcwd())
# mi_voldis first: it points Dr.Jit at a libLLVM that works before Mitsuba loads
import mi_voldis  # noqa: E402, I001
import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
from PIL import Image  # noqa: E402
from mi_voldis.cameras import DevicePoints, device_image  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from grid_probe import check_paths, grid_vertices  # noqa: E402

if len(sys.argv) != 5:
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
run, out = sys.argv[1], sys.argv[4]
try:
    view, reach = int(sys.argv[2]), float(sys.argv[3])
except ValueError:
    raise SystemExit(f"fog_views.py: VIEW {sys.argv[2]!r}, DIST {sys.argv[3]!r}: a view index and a number") from None
check_paths("fog_views.py", run, out)
r = mi_voldis.load_run(run)
ds = r.dataset
if view not in set(int(v) for v in ds.test):
    raise SystemExit(f"fog_views.py: view {view} is not one of the run's held-out views {list(map(int, ds.test))}")
os.makedirs(out)
z, inside, pts = grid_vertices(run)
at = DevicePoints(pts)
_, framed = at.pixel_of(ds.cameras[view])
fog = inside & framed.numpy() & (at.distance(ds.cameras[view]).numpy() < reach) & (z["data"][:, 0] > -2)
print(f"{run}: {fog.sum()} dense vertices within {reach} of view {view}'s camera, in its frame")


def depth_at(v):
    d = np.nan_to_num(r.render(view=v, layers=("full",))["depth"], nan=np.inf)
    pix, ok = at.pixel_of(ds.cameras[v])
    return d, pix.numpy(), ok.numpy(), dr.gather(mi.Float64, device_image(d, mi.Float64), pix, ok).numpy()


count, ratios = np.zeros(len(fog), int), []
for v in map(int, ds.train):
    d, pix, ok, at_depth = depth_at(v)
    count += ok
    here = ok & fog
    if here.any():
        ratios.append(at.distance(ds.cameras[v]).numpy()[here] / at_depth[here])
    if here.sum() >= 100:
        mask = np.zeros(d.shape, bool)
        mask.flat[pix[here]] = True
        fit = np.clip(r.render(view=v, layers=("full",), linear=False)["full"][..., :3], 0, 1)
        fin = np.where(np.isfinite(d), d, np.nan)
        dn = np.clip((fin - np.nanmin(fin)) / (np.nanpercentile(fin, 99) - np.nanmin(fin) + 1e-9), 0, 1)
        row = np.concatenate([ds.images[v], fit, np.repeat(np.nan_to_num(dn)[..., None], 3, 2),
                              np.where(mask[..., None], [1.0, 0, 0], ds.images[v])], 1)
        Image.fromarray((row * 255 + 0.5).astype(np.uint8)).save(os.path.join(out, f"train_view{v:03d}.png"))
        print(f"training view {v}: frames {here.sum()} of them on {mask.sum()} pixels; its expected depth there "
              f"{np.median(d[mask]):.3f}, over the whole view {np.median(d[np.isfinite(d)]):.3f}")
print("framed by 0, 1, 2, ... training views:", np.bincount(count[fog], minlength=6)[:8].tolist())
rat = np.concatenate(ratios)
print("distance / depth in each view that frames one (percentiles 5, 25, 50, 75, 95):",
      np.round(np.percentile(rat[np.isfinite(rat)], [5, 25, 50, 75, 95]), 3).tolist())
