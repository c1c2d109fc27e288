"""#46 probe: how many vertices the masks' free space takes under the rule of 5bbba03 (the mask eroded by a
pixel) and under today's (a vertex's reach kept off the mask's gaps), on one run's final lattice, and
GAPS.png: views 1, 11 and 20 beside their masks, in red the gaps a closing by a 13 x 13 square fills.

    python compare_rules.py RUN DATA GAPS.png
"""
import os
import subprocess
import sys
import tempfile
import types

import numpy as np
from PIL import Image

import mi_voldis  # noqa

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-11-30b"))
from probe_run import load_run

from mi_voldis.data.types import spread
from mi_voldis.fit import free_space as today
from mi_voldis.metrics import diagonal_pixels

run, data, sheet = sys.argv[1], sys.argv[2], sys.argv[3]
if os.path.exists(sheet):
    raise SystemExit(f"error: {sheet} exists")
root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..")
code = subprocess.run(["git", "-C", root, "show", "5bbba03:mi_voldis/fit/free_space.py"], check=True,
                      capture_output=True, text=True).stdout
before = types.ModuleType("mi_voldis.fit.free_space_5bbba03")
before.__package__ = "mi_voldis.fit"
exec(compile(code, "free_space@5bbba03", "exec"), before.__dict__)
cfg, ds, state, inputs = load_run(run, data)
full = state.fields["full"]
views = [ds.masked_train[k] for k in spread(len(ds.masked_train), today.VIEWS)]
args = ([ds.cameras[v] for v in views], ds.masks[views], diagonal_pixels(cfg.hull_dilation, ds.size),
        cfg.hull_min_views, cfg.free_space_margin)
a = before.free_vertices(full, inputs.space, *args)
b = today.free_vertices(full, inputs.space, *args)
print(f"free vertices: 5bbba03 {int(a.sum())}, today {int(b.sum())}, both {int((a & b).sum())}")
tiles = []
for v in (1, 11, 20):
    mask = ds.masks[v]
    gap = today.mask_gaps(mask, 6)
    vis = np.zeros(mask.shape + (3,), np.uint8)
    vis[mask], vis[gap] = 255, (255, 0, 0)
    tiles += [Image.open(os.path.join(data, "images", f"view_{v:03d}.png")).convert("RGB"), Image.fromarray(vis)]
w, h = tiles[0].size
out = Image.new("RGB", (len(tiles) * w, h))
for i, t in enumerate(tiles):
    out.paste(t, (i * w, 0))
with tempfile.TemporaryDirectory(dir=os.path.dirname(os.path.abspath(sheet))) as tmp:
    out.save(os.path.join(tmp, "sheet.png"))
    os.replace(os.path.join(tmp, "sheet.png"), sheet)
