"""#46 probe: how a run's full field stands against the true scene (a dataset carrying scene/scene.xml). For training
VIEWS: the render's PSNR against the photo and the expected depth over the true first-hit distance (median over the
pixels the field holds opaque); then the opacity per voxel by height above the floor plane y = 0 over the stored
vertices within RADIUS of the origin and more than 10 voxels (horizontally) from the masks' visual hull: the floor
away from the object.

    python field_probe.py RUN DATA VIEWS [RADIUS]
"""
import os
import sys

import numpy as np
from PIL import Image

import mi_voldis  # noqa: F401

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-11-30b"))
from probe_run import load_run  # noqa: E402

from mi_voldis.bench.geometry import load_truth, true_depth  # noqa: E402
from mi_voldis.field.state import density_of, vertex_positions  # noqa: E402
from mi_voldis.fit.background import voxel_of  # noqa: E402
from mi_voldis.fit.fields import fit_integrator  # noqa: E402
from mi_voldis.fit.hull import visual_hull  # noqa: E402
from mi_voldis.metrics import diagonal_pixels  # noqa: E402
from mi_voldis.render.views import render_camera  # noqa: E402

if len(sys.argv) not in (4, 5):
    raise SystemExit("usage: python field_probe.py RUN DATA VIEWS [RADIUS]")
run, data, views = sys.argv[1], sys.argv[2], [int(v) for v in sys.argv[3].split(",")]
radius = float(sys.argv[4]) if len(sys.argv) > 4 else 0.75
cfg, ds, state, inputs = load_run(run, data)
scene = load_truth(os.path.join(data, "scene", "scene.xml"))
integrator = fit_integrator(inputs, state)
for v in views:
    rgb, alpha, depth = render_camera(integrator, ds.cameras[v], ("full",))["full"]
    photo = np.asarray(Image.open(os.path.join(data, "images", f"view_{v:03d}.png")).convert("RGB"), float) / 255
    t = true_depth(scene, ds.cameras[v])
    ok = np.isfinite(t) & (alpha > 0.5)
    print(f"view {v}: {-10 * np.log10(np.mean((np.clip(rgb, 0, 1) - photo) ** 2)):.2f} dB against its photo, "
          f"expected depth / true {np.median(depth[ok] / t[ok]):.3f}")
full = state.fields["full"]
pos, real = vertex_positions(full)
world = inputs.space.to_world_np(pos[real])
vox = voxel_of(full)
alpha = 1 - np.exp(-np.logaddexp(0.0, density_of(full)[real]) * full.density_scale * vox)
cams, masks = [ds.cameras[v] for v in ds.masked_train], ds.masks[ds.masked_train]
hull = visual_hull(world, cams, masks, diagonal_pixels(cfg.hull_dilation, ds.size), cfg.hull_min_views)
near = np.zeros(len(world), bool)
for p in world[hull][:: max(1, hull.sum() // 4000)]:  # a subset of the hull's vertices: the distance is coarse
    near |= np.hypot(world[:, 0] - p[0], world[:, 2] - p[2]) < 10 * vox
floor = ~near & (np.hypot(world[:, 0], world[:, 2]) < radius)
for y in np.arange(0.0, 0.21, 0.05):
    band = floor & (np.abs(world[:, 1] - y) < vox / 2)
    print(f"floor away from the object, y = {y:.2f}: opacity per voxel {alpha[band].mean():.3f} "
          f"({band.sum()} vertices)")
