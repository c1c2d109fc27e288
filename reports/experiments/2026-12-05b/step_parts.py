"""Where a fit's training step goes, kernel by kernel, on a capture's last stage.

    python reports/experiments/2026-12-05b/step_parts.py DATASET OUT [--set KEY=VALUE ...] [--from STEP]

Runs the fit (the default, or with the settings given) with Dr.Jit's kernel history on from step ``--from``
and sorts each step's kernels by their width: as wide as the batch's rays (the march: primal, adjoint; the
loss's reductions), as wide as a field's packed floats or vertices (Adam, the gradients' sums, TV, sparsity:
the vertices' work; the history gives a fill's width in bytes, so the gradient's clearing counts here too),
and the rest. Prints, over steps with the TV and without, the median milliseconds of
each group, the kernels' total and the step's wall clock (the host's share is the difference), as JSON.
"""
import argparse
import json
import sys
import time

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
sys.path.insert(0, ".")
from mi_voldis.fit import problem as problem_module  # noqa: E402
from mi_voldis.fit.config import FitConfig  # noqa: E402
from mi_voldis.fit.run import run_fit  # noqa: E402

parser = argparse.ArgumentParser()
parser.add_argument("dataset")
parser.add_argument("out")
parser.add_argument("--set", action="append", default=[])
parser.add_argument("--from", dest="start", type=int, default=0)
args = parser.parse_args()

rows = []
last = {}
FieldFit = problem_module.FieldFit
before = FieldFit.before_step


def group(width, batch, lattice):
    if width >= lattice // 2:
        return "vertices"
    if width >= batch // 2 and width <= 4 * batch:
        return "rays"
    return "other"


def before_step(self, step):
    if step >= args.start:
        dr.sync_thread()
        now = time.perf_counter()
        if last:  # the kernels of the step just done
            batch = self.inputs.cfg.batch_rays
            lattice = min(f.layout.slots * f.layout.vertices_per_brick
                          for f in self.integrator.fields.values() if f.layout is not None)
            row = {"step": last["step"], "tv": float(last["step"] % self.inputs.cfg.tv_every == 0),
                   "wall": 1e3 * (now - last["t"]), "vertices": 0.0, "rays": 0.0, "other": 0.0, "kernels": 0}
            row["list"] = []
            for h in dr.kernel_history():
                if "execution_time" in h:
                    row["list"].append((int(h["size"]), round(h["execution_time"], 2)))
                    row[group(h["size"], batch, lattice)] += h["execution_time"]
                    row["kernels"] += 1
            row["lattice_vertices"] = lattice
            rows.append(row)
        else:
            dr.set_flag(dr.JitFlag.KernelHistory, True)
            dr.kernel_history()
        last.update(step=step, t=time.perf_counter())
    return before(self, step)


FieldFit.before_step = before_step
run_fit(args.dataset, args.out, FitConfig.from_sources(None, args.set), progress=False)
rows = [r for r in rows if r["wall"] < 5e3]  # a stage change or evaluation in between is not a step
out = {}
for label, keep in (("no_tv", 0.0), ("tv", 1.0)):
    sel = [r for r in rows if r["tv"] == keep]
    out[label] = {k: round(float(np.median([r[k] for r in sel])), 2) for k in ("wall", "rays", "vertices", "other",
                                                                                   "kernels")}
    out[label]["steps"] = len(sel)
out["lattice_vertices"] = rows[-1]["lattice_vertices"] if rows else None
for label, keep in (("kernels_no_tv", 0.0), ("kernels_tv", 1.0)):  # one step's kernels: (width, ms)
    out[label] = [r for r in rows if r["tv"] == keep][-1]["list"]
print(json.dumps(out, indent=1))
