"""#42: a small tabletop fit with sh_degree 'auto', to compare the held-out PSNR under two versions of the trial:
    python reports/experiments/2026-11-29/sh_trial/same_fit.py OUT"""
import json
import os
import sys

from mi_voldis.fit.config import FitConfig
from mi_voldis.fit.run import run_fit
from mi_voldis.synth.make import make_dataset

out = sys.argv[1]  # run twice, once with PYTHONPATH=<a checkout of the previous commit>
data = out + "_data"  # the tabletop rendered small, made once
if not os.path.exists(data):
    scene = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "..", "scenes", "tabletop.xml")
    make_dataset(scene, data, views=12, resolution=(40, 30), spp=4, progress=False)
sets = ["steps_full=160", "steps_bg=12", "lr_warmup=2", "resolution_schedule=[[0,12],[60,20],[110,28]]",
        "occupancy_at_step=20", "batch_rays=1024", "sh_degree=\"auto\"", "eval_every=1000", "preview_views=0"]
run_fit(data, out, FitConfig.from_sources(None, sets), progress=False)
m = json.load(open(os.path.join(out, "metrics.json")))
print(repr(m["held_out"]["psnr"]), repr(m["held_out"]["bg_psnr_mask"]), m["sh_choice"])
