"""#46: where family15's glassy box ghost lies in the background's start regions. For held-out VIEWS, every pixel's
ray is marched through the `guided` background kept by `2026-12-07d/garden_disc/kept_background.py` (OUT/state.npz)
and each sample's weight put in the region of the nearest stored vertex of the full field (outside the visual hull,
a kept hull vertex: some view sees it unmasked, a refilled one, the object's own). Writes OUT/regions_NNN.png: the
background layer beside the weight in the kept hull, the refilled and the object's regions (each scaled so that 0.5
is white), and prints the mean weight per region inside the scored hole.

    python ghost_regions.py RUN OUT DATA VIEWS
"""
import os
import sys

import numpy as np
from PIL import Image

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-12-07d", "garden_disc"))
from kept_background import REGIONS, kept_background, region_lookup, region_weights  # noqa: E402

from mi_voldis.cameras import pixel_rays  # noqa: E402
from mi_voldis.metrics import dilate, score_dilation  # noqa: E402
from mi_voldis.render.views import render_camera  # noqa: E402

if len(sys.argv) != 5:
    raise SystemExit("usage: python ghost_regions.py RUN OUT DATA VIEWS")
run, out, data, views = sys.argv[1], sys.argv[2], sys.argv[3], [int(v) for v in sys.argv[4].split(",")]
if os.path.realpath(out) in (os.path.realpath(run), os.path.realpath(data)):
    raise SystemExit(f"error: OUT {out} is the run or the dataset; give a folder of its own")
for v in views:
    if os.path.exists(os.path.join(out, f"regions_{v:03d}.png")):
        raise SystemExit(f"error: {out}/regions_{v:03d}.png exists; give another OUT")
ds, inputs, state, integrator = kept_background(run, out, data)
lookup = region_lookup(inputs, state)
for v in views:
    cam = ds.cameras[v]
    hole = dilate(ds.masks[v], score_dilation(ds.size))
    rgb = np.clip(ds.as_photographed(render_camera(integrator, cam, ("bg",))["bg"]), 0, 1)
    py, px = np.mgrid[0:cam.height, 0:cam.width]
    o, d = pixel_rays(cam, px.ravel() + 0.5, py.ravel() + 0.5)
    share = region_weights(integrator, lookup, o, d)
    share = share.reshape(cam.height, cam.width, 4)
    print(f"view {v}, hole ({hole.sum()} px): " + ", ".join(f"{n} {x:.3f}" for n, x in
                                                          zip(REGIONS, share[hole].mean(0))), flush=True)
    tiles = [rgb] + [np.repeat(np.clip(share[..., k:k + 1] / 0.5, 0, 1), 3, -1) for k in (1, 2, 3)]
    Image.fromarray((np.concatenate(tiles, 1) * 255).astype(np.uint8)).resize(
        (4 * cam.width * 3, cam.height * 3), Image.NEAREST).save(os.path.join(out, f"regions_{v:03d}.png"))
