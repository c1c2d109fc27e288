"""The surface survey of a calibrated fit and the grid each `min_observations` affords (reports/notes.md,
2026-11-26, the table of effective cells). Reproduces the table from a fit stopped after its `plan:` line:

    python scripts/train.py DATA --out RUN [--set space="contract"]   # Ctrl-C once it prints 'plan:'
    python reports/experiments/2026-11-26/plan_survey.py NAME DATA RUN.partial/checkpoints/last.npz [SPACE]

It renders 65,536 training rays of the checkpoint's fields (:func:`mi_voldis.fit.schedule.capture_survey`)
and evaluates :func:`mi_voldis.fit.schedule.affordable_resolution` for min_observations 16 to 256 (and
the default max_memory_gib; --set it high to see the observation bound alone)."""
import sys

import mi_voldis  # noqa: F401  (selects the variant, registers the plugins)
from mi_voldis.data import load_dataset
from mi_voldis.fit import schedule
from mi_voldis.fit.config import FitConfig
from mi_voldis.fit.fields import FitInputs, fit_integrator
from mi_voldis.fit.state import FitState
from mi_voldis.optim.adam import Adam

name, path, checkpoint = sys.argv[1:4]
space = sys.argv[4] if len(sys.argv) > 4 else "auto"
memory = float(sys.argv[5]) if len(sys.argv) > 5 else "auto"
dataset = load_dataset(path, "auto", 8, None)
cfg = FitConfig().replace(space=space, max_memory_gib=memory).for_backend("llvm")
inputs = FitInputs.of(dataset, cfg, "/dev/null", False)
state = FitState.load(checkpoint, Adam({}, 0.9, 0.99))
survey = schedule.capture_survey(inputs, fit_integrator(inputs, state), state)
plan = state.plan
budget = plan["budget_seconds"] - cfg.calibration_steps * plan["coarse_step_seconds"]
cost = schedule.StepCost(plan["coarse_step_seconds"], 64)  # llvm: the kernels are the step
afford = {m: schedule.affordable_resolution(cfg.replace(min_observations=m), cost, budget, survey, inputs.bank.pixels)
          for m in (16, 32, 64, 128, 256)}
print(name, "effective cells", round(survey["surface_cells"]), "ray hits", round(survey["ray_hits"], 3), "asks",
      survey["capture_resolution"], "affords by min_observations", afford)
