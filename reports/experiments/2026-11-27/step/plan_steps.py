"""The step 'auto' would choose for every default plan a committed report recorded (the coarse step's cost, the
budget and the survey), under today's constants for the backend given: the bounds costed at half a voxel and
at a whole one, and the step chosen. The training pixels are not recorded: they are taken as the fewest that
give the recorded pixel bound (a bound far above the others in every report here).

    python reports/experiments/2026-11-27/step/plan_steps.py REPORT.json [llvm|cuda]
    python reports/experiments/2026-11-27/step/plan_steps.py reports/family.json llvm
    python reports/experiments/2026-11-27/step/plan_steps.py reports/captures/gpu_2026-11-27.json cuda
"""
import json
import os
import sys

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4)))

from mi_voldis.fit.config import FitConfig  # noqa: E402
from mi_voldis.fit.schedule import WHOLE_VOXEL, StepCost, choose_step, resolution_bounds  # noqa: E402


def plans(node, path=""):
    """(path, plan) of every default plan in a report's JSON tree."""
    if isinstance(node, dict):
        if "resolution_bounds" in node and "coarse_step_seconds" in node:
            yield path, node
        for key, value in node.items():
            yield from plans(value, f"{path}/{key}")
    elif isinstance(node, list):
        for k, value in enumerate(node):
            yield from plans(value, f"{path}[{k}]")


def main(path, which="llvm"):
    cfg = FitConfig().for_backend(which)
    with open(path) as f:
        report = json.load(f)
    print(f"{path} ({which}): plan, bounds at half a voxel -> at one voxel, the step chosen")
    for where, plan in plans(report):
        host = plan.get("host_ms", 0.0) / 1e3
        coarse = plan["coarse_step_seconds"]
        cost = StepCost(coarse - host, 64, host)
        budget = plan["budget_seconds"] - cfg.calibration_steps * coarse
        survey = {k: plan[k] for k in ("surface_cells", "surface_resolution", "ray_hits")}
        cells = plan["surface_cells"] * (64 / plan["surface_resolution"]) ** 2
        pixels = int(cells * (plan["resolution_bounds"]["pixels"] / 64) ** 2 / plan["ray_hits"])
        half = resolution_bounds(cfg, cost, budget, survey, pixels)
        whole = resolution_bounds(cfg, cost.marching(WHOLE_VOXEL), budget, survey, pixels)
        print(f"{where}: {half} -> {whole}: {choose_step(cfg, cost, budget, survey, pixels):g} voxel")


if __name__ == "__main__":
    main(*sys.argv[1:])
