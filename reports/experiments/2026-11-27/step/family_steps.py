"""The step 'auto' would choose for each scene of the removal family, from the plans its committed report
recorded (reports/family.json: the coarse step's cost, the budget and the survey), under today's constants.
The pixels are not recorded: they are taken as the fewest that give the recorded pixel bound (a bound far
above the others).

    python reports/experiments/2026-11-27/step/family_steps.py [reports/family.json]
"""
import json
import os
import sys

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4)))

from mi_voldis.fit.config import FitConfig  # noqa: E402
from mi_voldis.fit.schedule import WHOLE_VOXEL, StepCost, choose_step, resolution_bounds  # noqa: E402


def main(path="reports/family.json"):
    cfg = FitConfig().for_backend("llvm")
    with open(path) as f:
        report = json.load(f)
    print(f"{path} ({report['date']}): scene, bounds at half a voxel -> at one voxel, the step chosen")
    for name, scene in report["scenes"].items():
        plan = scene["fit"]["metrics"]["schedule"]["plan"]
        coarse = plan["coarse_step_seconds"]
        cost = StepCost(coarse, 64)
        budget = plan["budget_seconds"] - cfg.calibration_steps * coarse
        survey = {k: plan[k] for k in ("surface_cells", "surface_resolution", "ray_hits")}
        cells = plan["surface_cells"] * (64 / plan["surface_resolution"]) ** 2
        pixels = int(cells * (plan["resolution_bounds"]["pixels"] / 64) ** 2 / plan["ray_hits"])
        half = resolution_bounds(cfg, cost, budget, survey, pixels)
        whole = resolution_bounds(cfg, cost.marching(WHOLE_VOXEL), budget, survey, pixels)
        print(f"{name}: {half} -> {whole}: {choose_step(cfg, cost, budget, survey, pixels):g} voxel")


if __name__ == "__main__":
    main(*sys.argv[1:])
