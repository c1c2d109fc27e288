"""Trial (not in the package): averaged iterates of the full field. Runs the default fit of DATASET with
averages of the full field's packed values kept over its last stage (Dr.Jit, every step): an EMA for
each beta in $BETAS (default 0.99,0.997) from the last stage's first step, and the plain mean of the
last $MEAN_FROM (default 0.25) of the planned steps. After the full phase every held-out view is rendered
by the fitted scene's rule
(`fit.fields.scene_integrator`) with the last iterate and with each average; the held-out PSNR of each is
printed and written to OUT.json, then the process ends (no background phase).

    [BETAS=b,b MEAN_FROM=f] python ema.py DATASET RUN OUT.json [--set name=value ...]

statue: `statue_ema.json` (defaults); garden: `garden_ema.json` (BETAS=0.997,0.999,0.9995 MEAN_FROM=0.5).
"""
import json
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
sys.path.insert(0, ROOT)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")
import numpy as np  # noqa: E402

from mi_voldis.fit import problem as problem_mod  # noqa: E402
from mi_voldis.fit import train  # noqa: E402
from mi_voldis.fit.fields import scene_integrator  # noqa: E402
from mi_voldis.metrics import psnr  # noqa: E402
from mi_voldis.render.views import render_camera  # noqa: E402

dataset, run_dir, out_json = sys.argv[1:4]
BETAS = tuple(float(b) for b in os.environ.get("BETAS", "0.99,0.997").split(","))
MEAN_FROM = float(os.environ.get("MEAN_FROM", "0.25"))
avg = {"problem": None, "ema": {}, "mean": None, "n": 0, "seconds": 0.0}

original_after = problem_mod.FieldFit.after_step


def after_step(self, step):
    original_after(self, step)
    st = self.state
    if "full" not in self.roles or self.phase != 0 or st.steps_full is None or len(st.schedule) < 2:
        return
    last = st.schedule[-1][0]
    if step < last:
        return
    t0 = time.perf_counter()
    avg["problem"] = self
    p = dr.detach(self.integrator.fields["full"].packed)
    for b in BETAS:
        e = avg["ema"].get(b)
        avg["ema"][b] = dr.detach(p) + 0.0 if e is None or dr.width(e) != dr.width(p) else dr.fma(e, b, p * (1 - b))
    if step >= int((1 - MEAN_FROM) * st.steps_full):
        n = avg["n"]
        m = avg["mean"]
        avg["mean"] = p + 0.0 if m is None or n == 0 else dr.fma(m, n / (n + 1), p * (1 / (n + 1)))
        avg["n"] = n + 1
    dr.eval(*avg["ema"].values(), *([avg["mean"]] if avg["mean"] is not None else []))
    avg["seconds"] += time.perf_counter() - t0


problem_mod.FieldFit.after_step = after_step
original_full = train.fit_full


def fit_full(inputs, state, roles, scratch, checkpoint):
    original_full(inputs, state, roles, scratch, checkpoint)
    ds, field = inputs.ds, state.fields["full"]
    last = dr.detach(field.data) + 0.0
    variants = {"last": last, **{f"ema{b}": e for b, e in avg["ema"].items()},
                f"mean_last{MEAN_FROM:g}_{avg['n']}": avg["mean"]}
    result = {"steps": state.steps_full, "schedule": state.schedule, "average_seconds": avg["seconds"]}
    for name, data in variants.items():
        field.data = data
        integ, _ = scene_integrator(inputs, state)
        values = []
        with dr.suspend_grad():
            for v in ds.test:
                img = np.clip(ds.as_photographed(render_camera(integ, ds.cameras[v], ("full",))["full"]), 0, 1)
                values.append(psnr(img, ds.images[v]))
        result[name] = {"psnr": float(np.mean(values)), "per_view": [float(x) for x in values]}
        print(f"{name}: held out {np.mean(values):.4f} dB", flush=True)
    field.data = last
    with open(out_json, "x") as f:
        json.dump(result, f, indent=1)
    os._exit(0)


train.fit_full = fit_full
from voldis_cli.train import main  # noqa: E402

main([dataset, "--out", run_dir, "--quiet", *sys.argv[4:]])
