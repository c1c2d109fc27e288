"""#42: a tiny grey degree-1 fit on a view lattice (onset at half the steps), to compare the held-out PSNR of
two versions of the code (the lattice read before the onset or not):

    PYTHONPATH=<checkout> python reports/experiments/2026-11-29g/gloss_keep_seen/unread_lattice_fit.py OUT
"""
import json
import os
import sys

from mi_voldis.fit.config import FitConfig
from mi_voldis.fit.run import run_fit
from mi_voldis.synth.make import make_dataset

out = sys.argv[1]
data = out + "_data"  # the tabletop rendered small, made once
if not os.path.exists(data):
    scene = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "..", "scenes", "tabletop.xml")
    make_dataset(scene, data, views=12, resolution=(40, 30), spp=4, progress=False)
sets = ["steps_full=160", "steps_bg=12", "lr_warmup=2", "resolution_schedule=[[0,12],[60,20],[110,28]]",
        "occupancy_at_step=20", "batch_rays=1024", "sh_degree=1", "sh_color=\"grey\"", "sh_view_resolution=6",
        "sh_view_from=0.5", "eval_every=1000", "preview_views=0"]
run_fit(data, out, FitConfig.from_sources(None, sets), progress=False)
with open(os.path.join(out, "metrics.json")) as f:
    print(repr(json.load(f)["held_out"]["psnr"]))
