"""The step a run's plan would choose (``step_voxels`` 'auto', :func:`mi_voldis.fit.schedule.choose_step`) at other
charges for the view lattice, from what the run recorded: its plan (the coarse step's cost, the budget, the capture
survey) and its dataset's training pixels. For each VIEW_STEP_COST: the plan's kernel_scale, the observations
bound at a whole voxel against the memory and pixel bounds, and the step chosen.

    python reports/experiments/2026-11-29h/grey_charged/step_choice.py RUN [RUN ...]
"""
import json
import os
import sys

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4)))

import mi_voldis.fit.schedule as schedule  # noqa: E402
from mi_voldis.data import load_dataset  # noqa: E402
from mi_voldis.fit.config import FitConfig  # noqa: E402

CHARGES = (1.0, 1.05, 1.1, 1.2, 1.3)


def main(runs):
    for run in runs:
        with open(os.path.join(run, "config.json")) as f:
            config = json.load(f)
        with open(os.path.join(run, "metrics.json")) as f:
            plan = json.load(f)["schedule"]["plan"]
        record = config["dataset"]
        cfg = FitConfig.from_sources(os.path.join(run, "config.json"))
        ds = load_dataset(record["path"], record["format"], record["holdout"], record["factor"])
        height, width = ds.images[ds.train[0]].shape[:2]
        pixels = len(ds.train) * height * width  # RayBank.pixels of the training views
        survey = {k: plan[k] for k in ("surface_cells", "surface_resolution", "ray_hits")}
        coarse = schedule.coarse_resolution(cfg)
        base = schedule.StepCost(plan["coarse_step_seconds"] - plan["host_ms"] / 1e3, coarse, plan["host_ms"] / 1e3)
        budget = plan["budget_seconds"] - cfg.calibration_steps * plan["coarse_step_seconds"]
        print(f"{os.path.basename(run.rstrip('/'))}: {pixels} training pixels, budget {budget:.0f} s")
        for charge in CHARGES:
            schedule.VIEW_STEP_COST = charge
            scale = schedule.degree_cost_scale(cfg, cfg.sh_degree)
            cost = schedule.StepCost(base.kernels * scale, coarse, base.host)
            whole = schedule.resolution_bounds(cfg, cost.marching(schedule.WHOLE_VOXEL), budget, survey, pixels)
            step = schedule.choose_step(cfg, cost, budget, survey, pixels)
            print(f"  VIEW_STEP_COST {charge}: kernel_scale {scale:.3f}, at a whole voxel observations "
                  f"{whole['observations']} / memory {whole['memory']} / pixels {whole['pixels']} -> step {step}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        raise SystemExit(__doc__.strip().splitlines()[-1].strip())
    main(sys.argv[1:])
