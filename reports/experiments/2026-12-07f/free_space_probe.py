"""#46 probe: clear the full field's density in the free space the masks prove: for each masked training view, the
stored vertices outside the visual hull that project inside its (eroded) mask nearer than the hull's nearest
vertex on that pixel: on a masked ray nothing but the object stands before the object. Writes a run copy OUT
(config.json, checkpoints/last.npz with the cleared full field) for `bench.strategies OUT guided ...`, and prints
the held-out PSNR of the full field before / after (each view's render against its photo in DATA/images).

    python free_space_probe.py RUN DATA OUT [MARGIN]
"""
import os
import shutil
import sys

import mitsuba as mi
import numpy as np
from PIL import Image

import mi_voldis  # noqa

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.cameras import DevicePoints
from mi_voldis.field.state import vertex_positions
from mi_voldis.fit.background import voxel_of
from mi_voldis.fit.fields import fit_integrator
from mi_voldis.fit.hull import visual_hull
from mi_voldis.metrics import diagonal_pixels, dilate
from mi_voldis.render.views import render_camera

if len(sys.argv) < 4:
    raise SystemExit("usage: python free_space_probe.py RUN DATA OUT [MARGIN]")
run, data, out = sys.argv[1], sys.argv[2], sys.argv[3]
margin = float(sys.argv[4]) if len(sys.argv) > 4 else 0.02
if os.path.exists(out):
    raise SystemExit(f"error: {out} exists")
cfg, ds, state, inputs = load_run(run, data)
full = state.fields["full"]
pos, real = vertex_positions(full)
world = inputs.space.to_world_np(pos)
idx_real = np.flatnonzero(real)
px = diagonal_pixels(cfg.hull_dilation, ds.size)
views = list(ds.masked_train)
cams, masks = [ds.cameras[v] for v in views], ds.masks[views]
voxel = voxel_of(full)


def min_filter(image, r):
    """The minimum over each pixel's (2r + 1)^2 neighbourhood (inf outside the image)."""
    padded = np.pad(image, r, constant_values=np.inf)
    out = np.full(image.shape, np.inf)
    for dy in range(2 * r + 1):
        for dx in range(2 * r + 1):
            out = np.minimum(out, padded[dy:dy + image.shape[0], dx:dx + image.shape[1]])
    return out


hull = np.zeros(len(world), bool)
hull[idx_real] = visual_hull(world[idx_real], cams, masks, px, cfg.hull_min_views)
print("hull vertices", hull.sum(), flush=True)
at_all = DevicePoints(world[idx_real])
hull_r = hull[idx_real]
free = np.zeros(len(idx_real), bool)
for cam, mask in zip(cams, masks):
    index, ok = at_all.pixel_of(cam)
    index, ok = np.array(index), np.array(ok)
    dist = np.array(at_all.distance(cam))
    H, W = mask.shape
    near = np.full(H * W, np.inf)
    sel = ok & hull_r
    np.minimum.at(near, index[sel], dist[sel])
    # a pixel no hull vertex projects into takes its neighbours' nearest (a voxel spans several pixels); one
    # with none around is left alone (what lies behind the object must not be cleared)
    reach = int(np.ceil(voxel / (np.median(dist[sel]) * np.radians(cam.fov_x) / cam.width))) + 1
    near = min_filter(near.reshape(H, W), reach).reshape(-1)
    inner = ~dilate(~mask, 1)  # the mask eroded by a pixel
    cand = ok & ~hull_r & inner.reshape(-1)[index]
    free |= cand & np.isfinite(near[index]) & (dist < (1 - margin) * near[index])
print("free vertices cleared", free.sum(), "of", len(idx_real), flush=True)
cleared = np.zeros(len(world), bool)
cleared[idx_real[free]] = True
integ = fit_integrator(inputs, state)
def heldout(integ):
    vals = []
    for v in ds.test:
        rgb = render_camera(integ, ds.cameras[v], ("full",))["full"][0]
        png = np.asarray(Image.open(os.path.join(data, "images", f"view_{v:03d}.png")).convert("RGB"), float) / 255
        vals.append(-10 * np.log10(np.mean((np.clip(rgb, 0, 1) - png) ** 2)))
    return vals
before = heldout(integ)
arr = np.array(full.bricks_data()).reshape(-1, full.width)
arr[cleared, 0] = -20.0
state.fields["full"] = full.with_bricks(mi.Float(arr.ravel()))
after = heldout(fit_integrator(inputs, state))
print("held-out full PSNR per view before", np.round(before, 2), "after", np.round(after, 2))
os.makedirs(os.path.join(out, "checkpoints"))
shutil.copy(os.path.join(run, "config.json"), out)
state.save(os.path.join(out, "checkpoints", "last.npz"), "bg", 0)
