"""The fit's schedule as data (mi_voldis/fit/schedule.py): analytic cases of every rule, and a fit with a
time budget that plans and rescales its stages."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from mi_voldis.fit.config import FitConfig
from mi_voldis.fit.schedule import (
    COST_EXPONENT,
    affordable_resolution,
    rescale,
    resolution_at,
    schedule_of,
    stages,
    steps_for,
)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_stages_double_up_to_the_final_resolution_and_start_at_the_given_fractions():
    cfg = FitConfig()
    assert stages(cfg, 64, 512) == [(0.0, 64), (0.1, 128), (0.2, 256), (0.35, 512)]
    assert stages(cfg, 64, 300) == [(0.0, 64), (0.2, 150), (0.35, 300)]
    assert stages(cfg, 64, 64) == [(0.0, 64)]
    assert stages(cfg.replace(stages=2), 64, 1024) == [(0.0, 64), (0.35, 1024)]


def test_steps_fill_the_budget_under_the_cost_model():
    plan = [(0.0, 64), (0.5, 128)]
    steps = steps_for(plan, 0.01, 100.0)
    cost = 0.01 * (0.5 * steps + 0.5 * steps * 2 ** COST_EXPONENT)
    assert abs(cost - 100.0) < 0.01 * 2 ** COST_EXPONENT + 1e-9
    assert schedule_of(plan, steps, 10) == [[0, 64], [round(0.5 * steps), 128]]
    assert schedule_of([(0.0, 64), (0.01, 128), (0.02, 256)], 100, 10) == [[0, 64], [11, 128], [12, 256]]
    assert [resolution_at([[0, 64], [11, 128], [12, 256]], s) for s in (0, 10, 11, 12, 99)] == [64, 64, 128, 256, 256]


def test_affordable_resolution_shows_every_pixel_min_epochs_times_in_the_last_stage():
    cfg = FitConfig()
    pixels, seconds, budget = 2_000_000, 0.01, 600.0
    r = affordable_resolution(cfg, 64, seconds, budget, pixels)
    steps = cfg.min_epochs * pixels / cfg.batch_rays
    last_share = 1.0 - cfg.stage_starts[-1]
    assert steps * seconds * (r / 64) ** COST_EXPONENT <= last_share * budget  # affordable
    assert steps * seconds * ((r + 16) / 64) ** COST_EXPONENT > last_share * budget  # the finest such
    assert r % 16 == 0


def test_rescale_fits_the_stages_ahead_to_the_budget_left():
    schedule, steps = [[0, 64], [200, 128], [400, 256]], 1000
    cost = 200 * 0.01 * 2 ** COST_EXPONENT + 600 * 0.01 * 4 ** COST_EXPONENT  # of what is ahead at step 200
    half, steps_half = rescale(schedule, steps, 200, 0.01, 64, cost / 2)
    assert half == [[0, 64], [200, 128], [300, 256]] and steps_half == 600
    double, steps_double = rescale(schedule, steps, 200, 0.01, 64, 2 * cost)
    assert double == [[0, 64], [200, 128], [600, 256]] and steps_double == 1800
    late, steps_late = rescale(schedule, steps, 400, 0.02, 128, 0.0)  # out of time: one step per stage left
    assert late == [[0, 64], [200, 128], [400, 256]] and steps_late == 401
    # within the last stage, timed on itself: 300 steps left at 0.05 s, 7.5 s of budget -> 150 steps
    mid, steps_mid = rescale(schedule, steps, 700, 0.05, 256, 7.5)
    assert mid == schedule and steps_mid == 850
    # within a stage that has one after it: both shrink in proportion, the current one keeps its start
    inner, steps_inner = rescale(schedule, steps, 300, 0.01, 128, (100 * 0.01 + 600 * 0.01 * 2 ** COST_EXPONENT) / 2)
    assert inner == [[0, 64], [200, 128], [350, 256]] and steps_inner == 650


def test_a_budgeted_fit_plans_from_the_capture_and_reports_its_plan(tiny_dataset, tmp_path):
    out = tmp_path / "run"
    sets = ["minutes=0.2", "calibration_steps=20", "coarse_resolution=8", "batch_rays=512", "steps_bg=4",
            "sh_degree=0", "eval_every=1000", "occupancy_at_step=10"]
    done = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "train.py"), tiny_dataset, "--out", str(out),
                           "--quiet"] + [x for s in sets for x in ("--set", s)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    metrics = json.load(open(out / "metrics.json"))
    plan, stages_ = metrics["schedule"]["plan"], metrics["schedule"]["stages"]
    assert plan["minutes"] == 0.2 and plan["final_resolution"] <= plan["capture_resolution"]
    assert stages_[0] == [0, 8] and stages_[-1][1] == plan["final_resolution"]
    assert [s for s, _ in stages_] == sorted({s for s, _ in stages_})  # starts strictly increasing
    if len(stages_) > 2:
        assert plan["rescaled"] and plan["rescaled"][-1][1] == metrics["schedule"]["steps_full"]
    log = json.load(open(out / "log.json"))
    assert [r["step"] for r in log if "psnr" in r][-1] == metrics["schedule"]["steps_full"]
    assert np.isfinite(metrics["held_out"]["psnr"])


@pytest.mark.parametrize("steps", [5, 17])
def test_the_optimisation_loop_follows_an_end_that_moves(steps):
    import mitsuba as mi

    from mi_voldis.optim.loop import optimize

    class Problem:  # stretches its own end at step 3
        keys = ["x"]

        def __init__(self):
            self.end, self.seen, self.params = 10, [], {"x": mi.Float(1.0)}

        def before_step(self, step):
            self.seen.append(step)
            if step == 3:
                self.end = steps

        def loss(self, step):
            return self.params["x"] * self.params["x"], {}

    class NoAdam:
        def step(self, params, grads, factor):
            pass
    p = Problem()
    log = optimize(p, NoAdam(), steps=lambda: p.end, progress=False)
    assert p.seen == list(range(max(steps, 4))) and [r["step"] for r in log] == list(range(1, max(steps, 4) + 1))


def test_rescale_keeps_min_steps_in_the_same_proportions_when_the_budget_is_spent():
    schedule, steps = [[0, 64], [200, 128], [400, 256]], 1000
    assert rescale(schedule, steps, 200, 0.01, 64, 1e9, 800)[1] > 1000  # the budget allows more: it rules
    spent, total = rescale(schedule, steps, 200, 0.01, 64, 0.0, 1800)  # 800 ahead -> 1600: each stage x 2
    assert spent == [[0, 64], [200, 128], [600, 256]] and total == 1800
    again = rescale(spent, total, 300, 0.01, 128, -5.0, 1800)  # still over budget: the plan does not drift
    assert again == (spent, total)
    inner, total = rescale(schedule, steps, 300, 0.01, 128, 0.0, 2100)  # 100 + 600 ahead -> 1800 (x 18 / 7)
    assert inner[:2] == schedule[:2] and inner[2][0] == 300 + round(100 * 18 / 7) and total == 2100
    short = rescale([[0, 64], [3, 128], [6, 256]], 9, 0, 0.01, 64, 0.0, 10)  # 3 x 3.33 rounds to 3 x 3
    assert short == ([[0, 64], [3, 128], [6, 256]], 10)  # the step short goes to the last stage


@pytest.mark.parametrize("minutes, floor", [("auto", 5000), (0.05, None)])
def test_the_default_budget_runs_at_least_min_steps_on_the_grid_it_picked(minutes, floor):
    from types import SimpleNamespace

    from mi_voldis.fit.train import plan_schedule
    cfg = FitConfig().replace(minutes=minutes, resolution=256, min_steps=5000)
    ds = SimpleNamespace(train=list(range(4)), size=(100, 100))  # 0.04 Mpx: the 1.5-minute floor
    state = SimpleNamespace(log=[{"step": s, "step_seconds": 0.01, "time": 0.01 * s} for s in range(1, 201)],
                            plan=None, steps_full=None, schedule=None)
    plan_schedule(SimpleNamespace(cfg=cfg, ds=ds), state, None)
    budgeted = steps_for(stages(cfg, 64, 256), 0.01, state.plan["budget_seconds"] - 2.0)
    assert state.plan.get("min_steps") == floor and state.schedule[-1][1] == 256
    assert state.steps_full == (max(budgeted, 5000) if floor else max(budgeted, 400))
    if floor:  # rescalings that find the budget spent keep the floor and the stages' shares
        from mi_voldis.fit.train import replan
        planned = [start for start, _ in state.schedule]
        for step in (300, 400, planned[2], planned[2] + 100):
            state.log += [{"step": s, "step_seconds": 1.0, "time": 1000.0} for s in range(len(state.log) + 1, step + 1)]
            replan(state, step)
            assert state.steps_full == 5000 and state.plan["rescaled"][-1] == [step, 5000]
            assert [start for start, _ in state.schedule] == planned
