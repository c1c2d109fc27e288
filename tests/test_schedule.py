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
    StepCost,
    affordable_resolution,
    degree_cost_scale,
    rescale,
    resolution_at,
    schedule_of,
    stages,
    steps_for,
)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_stages_double_up_to_the_final_resolution_and_start_at_the_given_fractions():
    cfg = FitConfig().for_backend("llvm")
    assert stages(cfg, 64, 512) == [(0.0, 64), (0.1, 128), (0.2, 256), (0.35, 512)]
    assert stages(cfg, 64, 300) == [(0.0, 64), (0.2, 150), (0.35, 300)]
    assert stages(cfg, 64, 64) == [(0.0, 64)]
    assert stages(cfg.replace(stages=2), 64, 1024) == [(0.0, 64), (0.35, 1024)]


def test_steps_fill_the_budget_under_the_cost_model():
    plan = [(0.0, 64), (0.5, 128)]
    steps = steps_for(plan, StepCost(0.01, 64), 100.0)
    cost = 0.01 * (0.5 * steps + 0.5 * steps * 2 ** COST_EXPONENT)
    assert abs(cost - 100.0) < 0.01 * 2 ** COST_EXPONENT + 1e-9
    assert schedule_of(plan, steps, 10) == [[0, 64], [round(0.5 * steps), 128]]
    assert schedule_of([(0.0, 64), (0.01, 128), (0.02, 256)], 100, 10) == [[0, 64], [11, 128], [12, 256]]
    assert [resolution_at([[0, 64], [11, 128], [12, 256]], s) for s in (0, 10, 11, 12, 99)] == [64, 64, 128, 256, 256]


SURVEY = {"surface_cells": 20_000.0, "surface_resolution": 64, "ray_hits": 0.9, "capture_resolution": 1024}
PIXELS = 40_000_000  # training pixels: enough for any grid below


def test_affordable_resolution_ends_min_observations_rays_in_every_surface_cell_of_the_last_stage():
    cfg = FitConfig().for_backend("llvm").replace(max_memory_gib=1e4)  # memory no bound here
    seconds, budget = 0.01, 600.0
    r = affordable_resolution(cfg, StepCost(seconds, 64), budget, SURVEY, PIXELS)
    last_share = 1.0 - cfg.stage_starts[-1]

    def observations(res):  # rays ending per surface cell over the last stage at resolution res
        steps = last_share * budget / (seconds * (res / 64) ** COST_EXPONENT)
        return steps * cfg.batch_rays * SURVEY["ray_hits"] / (SURVEY["surface_cells"] * (res / 64) ** 2)
    assert observations(r) >= cfg.min_observations > observations(r + 16)  # the finest such
    assert r % 16 == 0
    # the cells were counted on a finer grid: the same surface, the same answer
    finer = dict(SURVEY, surface_cells=SURVEY["surface_cells"] * 4, surface_resolution=128)
    assert affordable_resolution(cfg, StepCost(seconds, 64), budget, finer, PIXELS) == r
    # twice the budget buys a finer grid; a surface twice as large a coarser one; never below the coarse grid
    assert affordable_resolution(cfg, StepCost(seconds, 64), 2 * budget, SURVEY, PIXELS) > r
    assert affordable_resolution(cfg, StepCost(seconds, 64), budget, dict(SURVEY, surface_cells=4e4), PIXELS) < r
    assert affordable_resolution(cfg, StepCost(seconds, 64), 1e-3, SURVEY, PIXELS) == 64
    # few pixels: no more surface cells than pixels end on them, whatever the budget
    few = affordable_resolution(cfg, StepCost(seconds, 64), 1e6, SURVEY, 200_000)
    assert SURVEY["surface_cells"] * (few / 64) ** 2 <= 200_000 * SURVEY["ray_hits"] < \
        SURVEY["surface_cells"] * ((few + 16) / 64) ** 2


def memory_at(res, cells=SURVEY["surface_cells"], pixels=PIXELS, degree=0, grey=False):
    """The plan's estimate of a fit's peak bytes at ``res``, written out from its constants."""
    from mi_voldis.fit.schedule import BASE_BYTES, BYTES_PER_PIXEL, BYTES_PER_VERTEX, VERTICES_PER_SURFACE_CELL
    vertices = min(cells * (res / 64) ** 2 * VERTICES_PER_SURFACE_CELL, res ** 3)  # at most the dense lattice
    per_vertex = BYTES_PER_VERTEX * ((2.0 if grey else 4.0) if degree == 1 else 1.0)
    return BASE_BYTES + BYTES_PER_PIXEL * pixels + vertices * per_vertex


def test_affordable_resolution_keeps_the_estimated_memory_within_max_memory_gib():
    cfg = FitConfig().for_backend("llvm")
    r = affordable_resolution(cfg, StepCost(1e-6, 64), 1e6, SURVEY, PIXELS)  # time and pixels buy any grid
    assert memory_at(r) <= cfg.max_memory_gib * 2 ** 30 < memory_at(r + 16)
    # more memory: a finer grid
    assert r < affordable_resolution(cfg.replace(max_memory_gib=16.0), StepCost(1e-6, 64), 1e6, SURVEY, PIXELS)
    # surfaces counted everywhere on the coarse grid: the dense lattice's vertices bound the estimate
    everywhere = dict(SURVEY, surface_cells=64 ** 3)
    rd = affordable_resolution(cfg, StepCost(1e-6, 64), 1e6, everywhere, PIXELS)
    assert memory_at(rd, 64 ** 3) <= cfg.max_memory_gib * 2 ** 30 < memory_at(rd + 16, 64 ** 3)
    assert memory_at(rd, 64 ** 3) == memory_at(rd, 1e9) and rd > 64
    # the photos' share comes first: a capture whose pixels fill the memory gets the coarse grid
    from mi_voldis.fit.schedule import BYTES_PER_PIXEL
    assert affordable_resolution(cfg, StepCost(1e-6, 64), 1e6, SURVEY, 2 ** 32 // BYTES_PER_PIXEL) == 64


def test_a_stage_stops_short_of_the_memory_bound_on_its_counted_vertices():
    """fitting_resolution: the finest resolution (the planned one, or the current plus a multiple of 16)
    whose carved, resampled lattices hold at most the given vertices, counted without allocating them
    (the count equals what resampling allocates); the current resolution where none fits."""
    from types import SimpleNamespace

    from mi_voldis.field.state import new_field, resample, resampled_vertices, shape_for
    from mi_voldis.fit.fields import fitting_resolution
    lo, hi = np.zeros(3), np.array([1.0, 0.5, 1.0])
    field = new_field(lo, hi, 40, 0, -3.0, 1.0, 8)
    keep = np.zeros(field.layout.table.shape, bool)
    keep[0, :, :] = True  # a sheet of bricks: vertices grow with R^2
    state = SimpleNamespace(fields={"full": field, "bg": field}, lo=lo, hi=hi)
    count = lambda res: resampled_vertices(field, shape_for(lo, hi, res), keep)  # noqa: E731
    assert count(88) == resample(field, shape_for(lo, hi, 88), keep).vertices
    assert fitting_resolution(state, {"full": keep}, 200, count(200)) == 200  # fits: unchanged
    for limit in (count(88), count(88) + 1, count(104) - 1):
        got = fitting_resolution(state, {"full": keep}, 200, limit)
        assert (got - 40) % 16 == 0 and count(got) <= limit < count(got + 16), limit
    assert fitting_resolution(state, {"full": keep}, 200, 1) == 40  # nothing finer fits: stay
    assert fitting_resolution(state, {"full": keep, "bg": None}, 200, count(200) + 1) < 200  # fields add up


def test_capped_schedules_keep_earlier_stages_and_drop_repeats():
    from mi_voldis.fit.schedule import capped
    schedule = [[0, 64], [100, 128], [200, 256], [300, 512]]
    assert capped(schedule, 200, 200) == [[0, 64], [100, 128], [200, 200]]
    assert capped(schedule, 128, 200) == [[0, 64], [100, 128]]
    assert capped(schedule, 100, 0) == [[0, 64], [100, 100]]
    assert capped(schedule, 1024, 0) == schedule


def test_surface_cells_is_the_effective_number_of_cells_rays_end_in():
    from mi_voldis.fit.schedule import surface_cells
    rng = np.random.default_rng(0)
    for cells, draws in ((5000, 20000), (50000, 20000), (300, 100000)):  # S cells alike: S, however many draws
        counts = np.bincount(rng.integers(0, cells, draws))
        assert surface_cells(counts[counts > 0]) == pytest.approx(cells, rel=0.05)
    # 1000 cells take 90% of the ray ends, 100000 fog cells the rest: 1 / (0.9^2 / 1000 + 0.1^2 / 1e5) = 1234
    ends = np.concatenate([rng.integers(0, 1000, 90000), 1000 + rng.integers(0, 100000, 10000)])
    counts = np.bincount(ends)
    assert surface_cells(counts[counts > 0]) == pytest.approx(1 / (0.81 / 1000 + 0.01 / 1e5), rel=0.05)
    assert surface_cells([1, 1, 1]) == 3  # no cell hit twice: as many cells as ends


def test_rescale_fits_the_stages_ahead_to_the_budget_left():
    schedule, steps = [[0, 64], [200, 128], [400, 256]], 1000
    cost = 200 * 0.01 * 2 ** COST_EXPONENT + 600 * 0.01 * 4 ** COST_EXPONENT  # of what is ahead at step 200
    half, steps_half = rescale(schedule, steps, 200, StepCost(0.01, 64), cost / 2)
    assert half == [[0, 64], [200, 128], [300, 256]] and steps_half == 600
    double, steps_double = rescale(schedule, steps, 200, StepCost(0.01, 64), 2 * cost)
    assert double == [[0, 64], [200, 128], [600, 256]] and steps_double == 1800
    late, steps_late = rescale(schedule, steps, 400, StepCost(0.02, 128), 0.0)  # out of time: one step per stage left
    assert late == [[0, 64], [200, 128], [400, 256]] and steps_late == 401
    # within the last stage, timed on itself: 300 steps left at 0.05 s, 7.5 s of budget -> 150 steps
    mid, steps_mid = rescale(schedule, steps, 700, StepCost(0.05, 256), 7.5)
    assert mid == schedule and steps_mid == 850
    # within a stage that has one after it: both shrink in proportion, the current one keeps its start
    ahead = 100 * 0.01 + 600 * 0.01 * 2 ** COST_EXPONENT
    inner, steps_inner = rescale(schedule, steps, 300, StepCost(0.01, 128), ahead / 2)
    assert inner == [[0, 64], [200, 128], [350, 256]] and steps_inner == 650


def test_a_step_costs_the_hosts_fixed_time_plus_kernels_that_grow_with_the_resolution():
    cost = StepCost(0.004, 64, host=0.005)
    assert cost.at(64) == pytest.approx(0.009)
    assert cost.at(128) == pytest.approx(0.005 + 0.004 * 2 ** COST_EXPONENT)
    # a step timed at 9 ms on a backend whose host takes 5: the kernels took 4; a step shorter than the
    # host's estimate keeps a tenth of itself for its kernels
    timed, short = StepCost.timed(0.009, 64, 0.005), StepCost.timed(0.004, 64, 0.005)
    assert (timed.kernels, timed.resolution, timed.host) == (pytest.approx(0.004), 64, 0.005)
    assert (short.kernels, short.host) == (pytest.approx(0.0004), pytest.approx(0.0036))
    # the steps that fill a budget pay the host once each: 100 s at 9 ms (64^3) and 13.55 ms (128^3), half each
    plan = [(0.0, 64), (0.5, 128)]
    steps = steps_for(plan, cost, 100.0)
    assert steps == int(100.0 / (0.5 * cost.at(64) + 0.5 * cost.at(128)))
    # rescaled the same way: the budget ahead over the cost ahead
    ahead, end = rescale([[0, 64], [500, 128]], 1000, 500, cost, 500 * float(cost.at(128)) / 2)
    assert ahead == [[0, 64], [500, 128]] and end == 750


def test_a_host_bound_backend_affords_a_finer_grid_than_one_whose_step_grows_with_it():
    """At the same seconds a coarse step, a step mostly the host's (a GPU's) grows slowly with the
    resolution, so the same budget ends min_observations rays per cell on a finer grid."""
    cfg = FitConfig().for_backend("cuda").replace(max_memory_gib=1e4, batch_rays=8192)
    budget = 60.0
    kernels_only = affordable_resolution(cfg, StepCost(0.01, 64), budget, SURVEY, PIXELS)
    host_bound = affordable_resolution(cfg, StepCost(0.002, 64, host=0.008), budget, SURVEY, PIXELS)
    assert host_bound > kernels_only
    last_share = 1.0 - cfg.stage_starts[-1]
    cost = StepCost(0.002, 64, host=0.008)

    def observations(res):
        steps = last_share * budget / cost.at(res)
        return steps * cfg.batch_rays * SURVEY["ray_hits"] / (SURVEY["surface_cells"] * (res / 64) ** 2)
    assert observations(host_bound) >= cfg.min_observations > observations(host_bound + 16)


def test_the_plan_names_the_bound_that_chose_its_grid(monkeypatch):
    import mi_voldis.fit.train as train
    monkeypatch.setattr(train, "capture_survey", lambda *a: SURVEY)
    cfg = FitConfig().for_backend("llvm").replace(min_steps=0, max_memory_gib=0.05)  # memory binds first
    state = planned(cfg, calibrated(0.01, 0.01 * cfg.reference_msps * 1e6))
    bounds = state.plan["resolution_bounds"]
    assert state.plan["final_resolution"] == bounds["memory"] == min(bounds.values()) < bounds["observations"]
    assert "the memory (max_memory_gib) affords" in train.describe_plan(state)
    # with memory no bound, the few pixels of the test's views are
    state = planned(cfg.replace(max_memory_gib=1e4), calibrated(0.01, 0.01 * cfg.reference_msps * 1e6))
    bounds = state.plan["resolution_bounds"]
    assert state.plan["final_resolution"] == bounds["pixels"] == min(bounds.values()) < bounds["memory"]
    assert "the training pixels afford" in train.describe_plan(state)


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


def test_a_default_fit_counts_its_last_stage_and_fills_its_budget_by_the_count(tiny_dataset, tmp_path):
    """minutes 'auto' in a real fit: from REPLAN_EVERY steps into the last stage on, every replan costs a
    step by the median samples and stored floats its log counts there (past their first fifth), at the
    reference rates the plan recorded, and the steps ahead fill what the budget leaves: the fit ends where
    its last count says."""
    from mi_voldis.fit.schedule import REPLAN_EVERY, cost_ahead, counted_step_seconds, plan_cost
    out = tmp_path / "run"
    sets = ["calibration_steps=20", "coarse_resolution=8", "resolution=16", "batch_rays=256", "steps_bg=2",
            "sh_degree=0", "eval_every=1000", "occupancy_at_step=10", "min_steps=250", "stages=2",
            "stage_starts=[0.2]", "reference_msps=0.004", "sample_ns=5e4", "float_ns=1"]
    # rates of a slow reference machine: the tiny capture's budget (1.5 minutes) buys a few hundred steps
    done = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "train.py"), tiny_dataset, "--out", str(out),
                           "--quiet"] + [x for s in sets for x in ("--set", s)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    schedule = json.load(open(out / "metrics.json"))["schedule"]
    plan, steps = schedule["plan"], schedule["steps_full"]
    start = schedule["stages"][-1][0]
    counted = plan["recounted"]  # the last count: at the last replan before the end
    assert counted["step"] % REPLAN_EVERY == 0 and steps - REPLAN_EVERY <= counted["step"] < steps
    rows = [r for r in json.load(open(out / "log.json")) if start < r["step"] <= counted["step"] and "psnr" in r]
    rows = rows[len(rows) // 5:]
    assert all(r["floats"] > 0 for r in rows)
    seconds = counted_step_seconds(plan, np.median([r["samples"] for r in rows]),
                                   np.median([r["floats"] for r in rows]))
    assert counted["step_seconds"] == pytest.approx(seconds)
    before = plan["rescaled"]
    assert plan["rescaled"][-1][1] == steps
    cost = plan_cost(plan, 8)
    stages_ = schedule["stages"]
    spent = cost_ahead(stages_, steps, 0, cost) - cost_ahead(stages_, steps, start, cost) + \
        (counted["step"] - start) * seconds
    assert steps == counted["step"] + int((plan["budget_seconds"] - spent) / seconds) > 250, before
    log = json.load(open(out / "log.json"))
    assert [r["step"] for r in log if "psnr" in r][-1] == steps


def test_a_fit_whose_carved_grid_would_outgrow_the_memory_stays_on_the_grid_it_has(tiny_dataset, tmp_path,
                                                                                      monkeypatch):
    """With no memory for a single vertex more, every later stage is capped at the coarse grid: the run
    ends on it and its plan records each cap as [step, planned, used]."""
    from mi_voldis.field.state import shape_for
    from mi_voldis.fit import fields
    from mi_voldis.fit.run import run_fit
    monkeypatch.setattr(fields, "affordable_vertices", lambda *a: 1.0)
    sets = ["steps_full=90", "calibration_steps=40", "lr_density=0.5", "density_init_alpha=0.05", "coarse_resolution=8",
            "batch_rays=512", "steps_bg=2", "sh_degree=0", "eval_every=1000", "occupancy_at_step=10", "stages=3",
            "stage_starts=[0.4,0.7]"]
    out = str(tmp_path / "run")
    run_fit(tiny_dataset, out, FitConfig.from_sources(None, sets), progress=False)
    metrics = json.load(open(os.path.join(out, "metrics.json")))
    plan = metrics["schedule"]["plan"]
    assert plan["final_resolution"] > 8 and metrics["schedule"]["stages"] == [[0, 8]]
    assert plan["surface_cells"] > 0  # the plan chose the grid: the bound applies
    assert [c[2] for c in plan["memory_caps"]] == [8] and plan["memory_caps"][0][1] > 8
    box = metrics["box"]
    assert tuple(metrics["grid"]["full"]) == shape_for(np.array(box["lo"]), np.array(box["hi"]), 8)


def test_the_sample_bound_stops_refining_once_more_than_a_share_of_rays_reach_the_cap():
    """Rays at the cap beyond SAMPLE_CUT_SHARE keep the current grid; at or under it, or with rays that
    evaluate nothing, nothing is bound."""
    from mi_voldis.fit.fields import SAMPLE_CUT_SHARE, sample_bound
    n = 10000
    cut = int(n * SAMPLE_CUT_SHARE)
    over = np.concatenate([np.full(cut + 1, 512.0), np.full(n - cut - 1, 100.0)])
    within = np.concatenate([np.full(cut, 512.0), np.full(n - cut, 100.0)])
    assert sample_bound(64, over, 512) == 64
    assert sample_bound(64, within, 512) > 10 ** 6
    assert sample_bound(64, over, 513) > 10 ** 6  # the cap, not the count, decides
    assert sample_bound(64, np.zeros(10), 512) > 10 ** 6


def test_a_contracted_fit_whose_rays_would_pass_the_sample_cap_stays_on_the_grid_it_has(tiny_dataset, tmp_path):
    """With max_samples 1, what nearly every ray of the coarse grid already evaluates, a finer grid would cut
    them short: the plan stays on the coarse grid and records each cap as [step, planned, used]."""
    from mi_voldis.fit.run import run_fit
    sets = ["steps_full=90", "calibration_steps=40", "lr_density=0.5", "density_init_alpha=0.05", "coarse_resolution=8",
            "batch_rays=512", "steps_bg=2", "sh_degree=0", "eval_every=1000", "occupancy_at_step=10", "stages=3",
            "stage_starts=[0.4,0.7]", "space=contract", "max_samples=1"]
    out = str(tmp_path / "run")
    run_fit(tiny_dataset, out, FitConfig.from_sources(None, sets), progress=False)
    metrics = json.load(open(os.path.join(out, "metrics.json")))
    plan = metrics["schedule"]["plan"]
    assert metrics["space"] == "contract" and plan["final_resolution"] > 8
    assert metrics["schedule"]["stages"] == [[0, 8]] and "memory_caps" not in plan
    assert [c[2] for c in plan["samples_caps"]] == [8] and plan["samples_caps"][0][1] > 8
    # the same fit with the march's default cap refines past the coarse grid
    out = str(tmp_path / "run512")
    run_fit(tiny_dataset, out, FitConfig.from_sources(None, sets[:-1]), progress=False)
    metrics = json.load(open(os.path.join(out, "metrics.json")))
    assert metrics["schedule"]["stages"][-1][1] > 8 and "samples_caps" not in metrics["schedule"]["plan"]
    # its scene.xml strides through thin cells (contracted space), and renders what its metrics scored
    import mitsuba as mi

    from mi_voldis.data import load_dataset
    from mi_voldis.metrics import psnr
    from mi_voldis.render.views import render_camera
    integ = mi.load_file(os.path.join(out, "scene.xml")).integrator()
    assert integ.strides and integ.plan(("full",)).strides
    ds = load_dataset(tiny_dataset)
    v = ds.test[0]
    rendered = render_camera(integ, ds.cameras[v])  # every layer, as scored (their chains end the rays)
    assert abs(psnr(np.clip(ds.as_photographed(rendered["full"]), 0, 1), ds.images[v])
               - metrics["per_view"][0]["psnr"]) < 1e-3
    assert abs(rendered["evaluated"].mean() - metrics["per_view"][0]["samples_per_ray"]) < 1e-6
    # fitting strided too (strides): the same fit without them evaluates more samples in its training steps
    out = str(tmp_path / "plain")
    run_fit(tiny_dataset, out, FitConfig.from_sources(None, sets[:-1] + ["strides=\"none\""]), progress=False)
    plain = json.load(open(os.path.join(out, "metrics.json")))
    assert metrics["train_samples_per_ray"] < 0.9 * plain["train_samples_per_ray"]
    assert abs(metrics["held_out"]["psnr"] - plain["held_out"]["psnr"]) < 0.5


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


def test_the_loop_checkpoints_by_wall_clock_or_by_steps(monkeypatch):
    """A step taking 10 s of a fake clock: every third step passes 25 s since the last checkpoint; every
    fourth by steps; the last step checkpoints in both; without either rule, none."""
    from types import SimpleNamespace

    import mitsuba as mi

    from mi_voldis.optim import loop

    clock = [0.0]
    monkeypatch.setattr(loop, "time", SimpleNamespace(perf_counter=lambda: clock[0]))

    class Problem:
        keys = ["x"]
        params = {"x": mi.Float(1.0)}

        def before_step(self, step):
            clock[0] += 10.0

        def loss(self, step):
            return self.params["x"] * self.params["x"], {}

    class NoAdam:
        def step(self, params, grads, factor):
            pass

    def saves(**rule):
        out = []
        loop.optimize(Problem(), NoAdam(), steps=10, checkpoint=out.append, progress=False, **rule)
        return out
    assert saves(checkpoint_seconds=25.0) == [3, 6, 9, 10]
    assert saves(checkpoint_every=4) == [4, 8, 10]
    assert saves() == []


def calibrated(seconds, samples, steps=200):
    """A fit state just past its calibration steps, each taking ``seconds`` and evaluating ``samples``."""
    from types import SimpleNamespace
    log = [{"step": s, "step_seconds": seconds, "time": seconds * s, "samples": samples} for s in range(1, steps + 1)]
    return SimpleNamespace(log=log, plan=None, steps_full=None, schedule=None)


def default_step(cfg):
    """The coarse step a default plan is costed at in the tests below: 0.01 s of kernels at the reference
    speed (:func:`calibrated`'s samples), times the colour's charge (:func:`degree_cost_scale`: 1 for 'auto',
    which starts at degree 0; grey degree 1 on a view lattice costs the steps from ``sh_view_from`` on at
    ``VIEW_STEP_COST``), so the tests hold whichever colour is the default."""
    return StepCost(0.01 * degree_cost_scale(cfg, cfg.sh_degree), 64)


def planned(cfg, state, masks=None):
    from types import SimpleNamespace

    from mi_voldis.fit.train import plan_schedule
    ds = SimpleNamespace(train=list(range(4)), size=(100, 100), masks=masks)  # 0.04 Mpx: the 1.5-minute floor
    plan_schedule(SimpleNamespace(cfg=cfg, ds=ds, bank=SimpleNamespace(pixels=4 * 100 * 100)), state, None)
    return state


PLANS = {}  # load -> (schedule, steps) of the parametrised test below
COUNTED = {}  # load -> its steps once the last stage is counted


@pytest.mark.parametrize("load", [1.0, 3.0, 0.2])
def test_the_default_plan_is_costed_at_the_reference_speed_whatever_the_machine(load):
    """minutes 'auto': a coarse step costs its samples over reference_msps, however long it took here;
    the budget decides the steps, min_steps their floor, and nothing is re-timed while the fit runs: the
    last stage is costed from the samples and floats its steps count."""
    cfg = FitConfig().for_backend("llvm").replace(resolution=256, min_steps=500)
    samples = 0.01 * cfg.reference_msps * 1e6  # 0.01 s a coarse step at the reference speed
    state = planned(cfg, calibrated(0.01 * load, samples))
    budget = state.plan["budget_seconds"] - cfg.calibration_steps * 0.01
    assert state.plan["coarse_step_seconds"] == pytest.approx(0.01)
    assert state.steps_full == max(steps_for(stages(cfg, 64, 256), default_step(cfg), budget), 500)
    PLANS[load] = (state.schedule, state.steps_full)
    assert PLANS[load] == PLANS.get(1.0, PLANS[load])  # a faster or slower machine plans the same fit
    from mi_voldis.fit.schedule import cost_ahead, plan_cost
    from mi_voldis.fit.train import replan
    before = (list(state.schedule), state.steps_full)
    start = state.schedule[-1][0]
    floats = 3e6
    state.log += [{"step": s, "step_seconds": load, "time": 1000.0 * load, "samples": samples, "floats": floats}
                  for s in range(len(state.log) + 1, start + 101)]
    for step in (300, start, start + 50):  # before the last stage, or too few of its steps: nothing changes
        replan(state, step)
    assert (state.schedule, state.steps_full) == before and "rescaled" not in state.plan
    # REPLAN_EVERY steps into the last stage its steps are costed from what they count, not timed
    replan(state, start + 100)
    seconds = (samples * state.plan["sample_ns"] + floats * state.plan["float_ns"]) * 1e-9
    assert state.plan["recounted"] == {"step": start + 100, "step_seconds": pytest.approx(seconds)}
    cost = plan_cost(state.plan, 64)
    spent = cost_ahead(before[0], before[1], 0, cost) - cost_ahead(before[0], before[1], start, cost) + 100 * seconds
    assert state.steps_full == max(start + 100 + int((state.plan["budget_seconds"] - spent) / seconds), 500)
    assert state.schedule == before[0]
    COUNTED[load] = state.steps_full
    assert COUNTED[load] == COUNTED.get(1.0, COUNTED[load])  # a faster or slower machine counts the same
    after = state.steps_full
    replan(state, start + 200)  # the same counts: the end stays
    assert state.steps_full == after and len(state.plan["rescaled"]) == 1
    state.log += [dict(r, step=s, samples=4 * samples) for s, r in
                  zip(range(start + 101, start + 501), [state.log[-1]] * 400)]
    replan(state, start + 500)  # steps that now count more samples: fewer of them fit the budget
    assert state.plan["recounted"]["step"] == start + 500 and state.plan["recounted"]["step_seconds"] > seconds
    assert state.steps_full < after or state.steps_full == 500


def test_a_default_plan_capped_by_memory_spends_the_seconds_it_saves_on_steps_at_the_cap():
    """Memory stops the last stage of a default plan below its resolution: the seconds the plan gave the
    steps ahead buy more steps at the capped resolution (cost R^COST_EXPONENT a step), those before the
    cap unchanged, as far as the budget goes; the plan's own cost (:func:`plan_cost`) is the one it was
    made with."""
    from mi_voldis.fit.schedule import cost_ahead, plan_cost, rescale_after_cap
    cfg = FitConfig().for_backend("llvm").replace(resolution=256, min_steps=500)
    state = planned(cfg, calibrated(0.01, 0.01 * cfg.reference_msps * 1e6))
    cost = plan_cost(state.plan, state.schedule[0][1])
    assert cost.at([64, 256]) == pytest.approx(default_step(cfg).at([64, 256]))
    (start, last), end, budget = state.schedule[-1], state.steps_full, state.plan["budget_seconds"]
    schedule, steps = rescale_after_cap(state.schedule, end, start, 192, cost, budget)
    assert schedule == state.schedule[:-1] + [[start, 192]]
    assert steps - start == round((end - start) * (last / 192) ** COST_EXPONENT)  # analytic, host 0
    assert cost_ahead(schedule, steps, start, cost) == pytest.approx(cost_ahead(state.schedule, end, start, cost),
                                                                     rel=1e-3)
    # capped at the resolution before it, the last stage merges into that one and still fills the seconds
    prev = state.schedule[-2][1]
    schedule, steps = rescale_after_cap(state.schedule, end, start, prev, cost, budget)
    assert schedule == state.schedule[:-1] and steps - start == round((end - start) * (last / prev) ** COST_EXPONENT)
    # a plan held at min_steps over its budget keeps its steps: the cap saves seconds it never had
    schedule, steps = rescale_after_cap(state.schedule, end, start, 192, cost, budget / 10)
    assert schedule == state.schedule[:-1] + [[start, 192]] and steps == end


def test_the_default_resolution_is_the_finest_the_reference_speed_affords(monkeypatch):
    import mi_voldis.fit.train as train
    monkeypatch.setattr(train, "capture_survey", lambda *a: SURVEY)  # the capture asks for more than it buys
    cfg = FitConfig().for_backend("llvm").replace(min_steps=0)
    samples = 0.01 * cfg.reference_msps * 1e6
    for load in (1.0, 4.0):
        state = planned(cfg, calibrated(0.01 * load, samples))
        budget = state.plan["budget_seconds"] - cfg.calibration_steps * 0.01
        assert state.plan["final_resolution"] == affordable_resolution(cfg, default_step(cfg), budget, SURVEY,
                                                                       4 * 100 * 100) < 1024


def test_a_large_captures_extra_minutes_buy_steps_on_the_grid_ten_minutes_pick(monkeypatch):
    """Past the llvm bound's 12 Mpx the budget grows (here to 15 minutes), but the grid is the one the
    10-minute budget affords: the extra minutes buy steps on it."""
    from types import SimpleNamespace

    import mi_voldis.fit.train as train
    monkeypatch.setattr(train, "capture_survey", lambda *a: SURVEY)
    monkeypatch.setattr(train, "backend", lambda: "llvm")
    cfg = FitConfig().for_backend("llvm").replace(min_steps=0, max_memory_gib=1e4)
    samples = 0.01 * cfg.reference_msps * 1e6
    plans = {}
    for views in (60, 400):  # 12 Mpx: 10 minutes; 80 Mpx: 15
        ds = SimpleNamespace(train=list(range(views)), size=(500, 400), masks=None)
        state = calibrated(0.01, samples)
        train.plan_schedule(SimpleNamespace(cfg=cfg, ds=ds, bank=SimpleNamespace(pixels=PIXELS)), state, None)
        plans[views] = state
    small, large = plans[60], plans[400]
    assert small.plan["minutes"] == 10.0 and "grid_minutes" not in small.plan
    assert large.plan["minutes"] == 15.0 and large.plan["grid_minutes"] == 10.0
    assert large.plan["final_resolution"] == small.plan["final_resolution"] < SURVEY["capture_resolution"]
    assert large.plan["step_voxels"] == small.plan["step_voxels"]
    assert large.steps_full == pytest.approx(small.steps_full * 15 / 10, rel=0.01)


def test_a_large_capture_at_the_floor_places_every_stage_over_the_steps_its_extra_minutes_buy(monkeypatch):
    """A capture whose budget grew past the bound (15 minutes of the bound's 10) and whose plan sits at the
    min_steps floor places its stages over min_steps x 15 / 10 steps, where its last stage will be
    counted (the count then sets the end, at least min_steps); a capture within the bound, or one whose
    count is off (sample_ns null), places them over min_steps."""
    from types import SimpleNamespace

    import mi_voldis.fit.train as train
    from mi_voldis.fit.schedule import plan_cost
    monkeypatch.setattr(train, "capture_survey", lambda *a: SURVEY)
    monkeypatch.setattr(train, "backend", lambda: "llvm")
    cfg = FitConfig().for_backend("llvm").replace(min_steps=20_000, max_memory_gib=1e4)
    samples = 0.01 * cfg.reference_msps * 1e6

    def plan(views, cfg):
        ds = SimpleNamespace(train=list(range(views)), size=(500, 400), masks=None)
        state = calibrated(0.01, samples)
        train.plan_schedule(SimpleNamespace(cfg=cfg, ds=ds, bank=SimpleNamespace(pixels=PIXELS)), state, None)
        return state

    small, large, uncounted = plan(60, cfg), plan(400, cfg), plan(400, cfg.replace(sample_ns=None))
    assert large.plan["minutes"] == 15.0 and large.plan["grid_minutes"] == 10.0
    budgeted = steps_for(stages(cfg, 64, large.plan["final_resolution"]), plan_cost(large.plan, 64),
                         large.plan["budget_seconds"] - cfg.calibration_steps * 0.01)
    assert budgeted < 20_000  # the floor, not the budget, places the stages
    assert small.steps_full == uncounted.steps_full == 20_000 and large.steps_full == 30_000
    assert large.plan["min_steps"] == 20_000  # the end's floor stays: the count may end it below 30,000
    later = [float(f) for f in cfg.stage_starts][1 - len(large.schedule):]  # the later stages' fractions
    assert [s for s, _ in large.schedule] == [0] + [round(f * 30_000) for f in later]
    assert [r for _, r in large.schedule] == [r for _, r in uncounted.schedule]


def test_the_default_budget_runs_at_least_min_steps_on_the_grid_it_picked():
    cfg = FitConfig().for_backend("llvm").replace(resolution=256, min_steps=5000)
    state = planned(cfg, calibrated(0.5, 0.01 * cfg.reference_msps * 1e6))  # a slow machine changes nothing
    budgeted = steps_for(stages(cfg, 64, 256), default_step(cfg), state.plan["budget_seconds"] - 2.0)
    assert budgeted < 5000 and state.plan["min_steps"] == 5000 and state.schedule[-1][1] == 256
    assert state.steps_full == 5000


def test_a_capture_without_masks_gives_its_full_field_the_background_refits_share():
    """The background refit's share of the budget (RESERVED) goes to the full field where no background
    is refitted (no masks, or 'scratch', which fits both fields in the full phase): its steps grow in proportion."""
    from mi_voldis.fit.schedule import RESERVED, RESERVED_NO_BACKGROUND
    cfg = FitConfig().for_backend("llvm").replace(resolution=256, min_steps=0)
    samples = 0.01 * cfg.reference_msps * 1e6
    plans = {masks is not None: planned(cfg.replace(bg_strategy=strategy), calibrated(0.01, samples), masks)
             for masks, strategy in ((None, "guided"), (["mask"], "guided"))}
    scratch = planned(cfg.replace(bg_strategy="scratch"), calibrated(0.01, samples), ["mask"])
    minutes = plans[False].plan["minutes"]
    assert plans[True].plan["budget_seconds"] == pytest.approx(minutes * 60 * (1 - RESERVED))
    assert plans[False].plan["budget_seconds"] == pytest.approx(minutes * 60 * (1 - RESERVED_NO_BACKGROUND))
    assert scratch.plan["budget_seconds"] == plans[False].plan["budget_seconds"]
    for masked, state in plans.items():
        budget = state.plan["budget_seconds"] - cfg.calibration_steps * 0.01
        assert state.steps_full == steps_for(stages(cfg, 64, 256), default_step(cfg), budget)
    assert plans[False].steps_full > plans[True].steps_full * 1.15


def test_a_budget_in_minutes_is_timed_here_and_rescaled_as_the_fit_runs():
    cfg = FitConfig().for_backend("llvm").replace(minutes=0.5, resolution=64)  # one stage: a replan times it
    slow, fast = (planned(cfg, calibrated(s, 1e5)) for s in (0.02, 0.01))
    assert "min_steps" not in slow.plan and slow.plan["coarse_step_seconds"] == 0.02
    assert fast.steps_full > slow.steps_full > 500  # the same budget buys a faster machine more steps
    from mi_voldis.fit.train import replan
    fast.log += [{"step": s, "step_seconds": 0.04, "time": 2.0 + 0.04 * (s - 200), "samples": 1e5}
                 for s in range(201, 501)]
    before = fast.steps_full
    replan(fast, 500)  # it now runs at a quarter of the planned speed: fewer steps ahead
    assert fast.plan["rescaled"] == [[500, fast.steps_full]]
    assert fast.steps_full == 500 + round((fast.plan["budget_seconds"] - fast.log[-1]["time"]) / 0.04) < before


def test_the_plan_is_reported_in_one_line():
    from types import SimpleNamespace

    from mi_voldis.fit.train import describe_plan
    state = SimpleNamespace(schedule=[[0, 64], [600, 144], [1050, 288]], steps_full=4952,
                            plan={"capture_resolution": 800, "affordable_resolution": 288, "minutes": 8.1,
                                  "reference_msps": 18.0})
    assert describe_plan(state) == ("resolution 64 (step 0) -> 144 (step 600) -> 288 (step 1050), 4952 steps "
                                    "(8.1 min at the reference speed); the capture asks 800, the budget affords 288")
    state.plan = {"capture_resolution": 96, "affordable_resolution": 128, "minutes": 2.0}  # timed, capture-bound
    assert describe_plan(state).endswith("(2.0 min of this machine's wall clock); the capture asks 96")


def test_the_default_plan_follows_the_backend(monkeypatch):
    """'auto' batch, reference speed, host time, memory and budget are the backend's: on cuda a coarse step
    of the same samples costs the host's fixed milliseconds plus its kernels at the faster speed, the budget
    is shorter, the batch larger, the memory bound higher."""
    from types import SimpleNamespace

    import mi_voldis.fit.train as train
    from mi_voldis.fit.schedule import BACKENDS, auto_minutes
    big = SimpleNamespace(train=list(range(60)), size=(500, 400))  # 12 Mpx
    assert auto_minutes(big, "llvm") == 10.0 and auto_minutes(big, "cuda") == 5.0
    # past 12 Mpx the llvm bound grows as the cube root of the pixels, at most 15 minutes; cuda's stays
    bigger = SimpleNamespace(train=list(range(180)), size=(500, 400))  # 36 Mpx
    assert auto_minutes(bigger, "llvm") == pytest.approx(10.0 * 3 ** (1 / 3)) and auto_minutes(bigger, "cuda") == 5.0
    huge = SimpleNamespace(train=list(range(1000)), size=(500, 400))
    assert auto_minutes(huge, "llvm") == 15.0
    small = SimpleNamespace(train=list(range(4)), size=(100, 100))
    assert auto_minutes(small, "llvm") == 1.5 and auto_minutes(small, "cuda") == 1.0
    plans = {}
    for which in ("llvm", "cuda"):
        monkeypatch.setattr(train, "backend", lambda w=which: w)
        cfg = FitConfig().replace(resolution=256, min_steps=0).for_backend(which)
        b = BACKENDS[which]
        assert (cfg.batch_rays, cfg.reference_msps, cfg.host_ms, cfg.max_memory_gib) == \
            (b.batch_rays, b.reference_msps, b.host_ms, b.max_memory_gib)
        plans[which] = planned(cfg, calibrated(0.01, 0.01 * 18e6)).plan  # the same samples a coarse step
    assert plans["llvm"]["coarse_step_seconds"] == pytest.approx(0.01)
    cuda = BACKENDS["cuda"]
    assert plans["cuda"]["coarse_step_seconds"] == pytest.approx(cuda.host_ms / 1e3 + 0.01 * 18 / cuda.reference_msps)
    assert plans["cuda"]["host_ms"] == cuda.host_ms > 0 == plans["llvm"]["host_ms"]
    assert plans["cuda"]["minutes"] == 1.0 and plans["llvm"]["minutes"] == 1.5
    # explicit values stay
    cfg = FitConfig().replace(batch_rays=1000, reference_msps=5.0, host_ms=0.0, max_memory_gib=2.0).for_backend("cuda")
    assert (cfg.batch_rays, cfg.reference_msps, cfg.host_ms, cfg.max_memory_gib) == (1000, 5.0, 0.0, 2.0)


def test_degree_one_colour_is_bounded_in_memory_as_its_four_times_wider_vertices_ask():
    from types import SimpleNamespace

    from mi_voldis.fit.schedule import BYTES_PER_VERTEX, memory_resolution, memory_scale, resolution_bounds
    from mi_voldis.fit.train import cap_for_sh_degree
    assert memory_scale(0) == memory_scale("auto") == 1.0 and memory_scale(1) == 4.0  # 16 floats a vertex, not 4
    assert memory_scale(1, grey=True) == 2.0 and memory_scale(0, grey=True) == 1.0  # grey: 7 floats in 8
    cfg = FitConfig().for_backend("llvm").replace(sh_color="rgb")
    cells = 2000.0  # at 64^3
    r0, r1 = (memory_resolution(cfg, cells, 64, 64, d, PIXELS) for d in (0, 1))
    for r, d in ((r0, 0), (r1, 1)):
        assert memory_at(r, cells, degree=d) <= cfg.max_memory_gib * 2 ** 30 < memory_at(r + 16, cells, degree=d)
    assert 64 < r1 < r0
    rg = memory_resolution(cfg.replace(sh_color="grey", sh_view_resolution=None), cells, 64, 64, 1, PIXELS)
    assert memory_at(rg, cells, degree=1, grey=True) <= cfg.max_memory_gib * 2 ** 30 < memory_at(rg + 16, cells,
                                                                                              degree=1, grey=True)
    assert r1 < rg < r0
    # grey on a view lattice: the bricks cost degree 0's, the lattice (64^3 vertices) is counted once
    rv = memory_resolution(cfg.replace(sh_color="grey"), cells, 64, 64, 1, PIXELS)
    view = 64 ** 3 * BYTES_PER_VERTEX
    assert rg < rv <= r0
    assert memory_at(rv, cells) + view <= cfg.max_memory_gib * 2 ** 30 < memory_at(rv + 16, cells) + view
    survey = dict(SURVEY, surface_cells=cells)
    assert resolution_bounds(cfg.replace(sh_degree=1), StepCost(1e-6, 64), 1e6, survey, PIXELS)["memory"] == r1
    # 'auto' picks degree 1 after a plan made at degree 0: the finer stages take the degree-1 bound
    plan = {"surface_cells": cells, "surface_resolution": 64}

    def inputs(c):
        return SimpleNamespace(cfg=c, bank=SimpleNamespace(pixels=PIXELS), ds=SimpleNamespace(masks=None))
    state = SimpleNamespace(plan=dict(plan), schedule=[[0, 64], [300, r1 + 32], [500, r0]])
    cap_for_sh_degree(inputs(cfg), state, 1, 300)
    assert state.schedule == [[0, 64], [300, r1]] and state.plan["sh_memory_cap"] == r1
    kept = [[0, 64], [300, r1]]
    state = SimpleNamespace(plan=dict(plan), schedule=[list(s) for s in kept])
    cap_for_sh_degree(inputs(cfg), state, 1, 300)  # already within: unchanged, nothing recorded
    assert state.schedule == kept and "sh_memory_cap" not in state.plan
    state = SimpleNamespace(plan=dict(plan), schedule=[[0, 64], [500, r0]])
    cap_for_sh_degree(inputs(cfg.replace(resolution=r0)), state, 1, 500)  # a resolution the user gave stays
    assert state.schedule == [[0, 64], [500, r0]]



def degree_one_at_step_300(cfg):
    """'auto' turning a default plan (costed at the reference speed; stages 64, 128 from step 300, 192 from
    600, 3000 steps) to degree 1 at step 300 under ``cfg``: (plan before, state after, the seconds the plan
    gave the steps from 300 on)."""
    from types import SimpleNamespace

    from mi_voldis.fit.schedule import cost_ahead, plan_cost
    from mi_voldis.fit.train import cap_for_sh_degree
    plan = {"surface_cells": 10.0, "surface_resolution": 64, "reference_msps": 18.0, "coarse_step_seconds": 0.04,
            "host_ms": 0.0, "step_voxels": 0.5}
    schedule, steps = [[0, 64], [300, 128], [600, 192]], 3000
    state = SimpleNamespace(plan=dict(plan), schedule=[list(s) for s in schedule], steps_full=steps)
    inputs = SimpleNamespace(cfg=cfg, bank=SimpleNamespace(pixels=PIXELS), ds=SimpleNamespace(masks=None))
    before = cost_ahead(schedule, steps, 300, plan_cost(plan, 64))
    cap_for_sh_degree(inputs, state, 1, 300)
    return plan, state, before


def test_degree_one_chosen_in_a_default_plan_costs_its_steps_at_degree_one():
    """A default plan (costed at the reference speed) that 'auto' turns to grey degree-1 colour at every
    vertex at step 300: the seconds it gave the steps ahead (at degree 0's cost) buy steps whose kernels
    cost memory_scale (2) times as much, and the plan's cost says so from then on."""
    from mi_voldis.fit.schedule import cost_ahead, memory_scale, plan_cost
    assert memory_scale(1, grey=True) == 2.0
    plan, state, before = degree_one_at_step_300(
        FitConfig().for_backend("llvm").replace(sh_color="grey", sh_view_resolution=None))
    steps = 3000
    assert state.plan["kernel_scale"] == 2.0 and "sh_memory_cap" not in state.plan  # 192 is within memory
    assert state.schedule[:2] == [[0, 64], [300, 128]] and [r for _, r in state.schedule] == [64, 128, 192]
    assert plan_cost(state.plan, 64).kernels == pytest.approx(2 * plan_cost(plan, 64).kernels)
    after = cost_ahead(state.schedule, state.steps_full, 300, plan_cost(state.plan, 64))
    assert after == pytest.approx(before, rel=2e-3)  # the same seconds (to a step's rounding) ...
    assert state.steps_full - 300 == pytest.approx((steps - 300) / 2, abs=2)  # ... for half the steps
    assert state.plan["rescaled"] == [[300, state.steps_full]]


def test_a_view_lattice_costs_its_steps_from_the_onset_on():
    """Grey degree 1 on a view lattice: the steps before ``sh_view_from`` cost degree 0's (the all-0 lattice
    is not read), those after VIEW_STEP_COST times as much; averaged over the steps from ``start`` on. A
    plan made at degree 1 records that scale, and its steps cost it: the budget buys 1 / scale of degree 0's
    steps on the same grids. 'auto' turning to it at step 300 of 3000 costs the steps ahead the same way."""
    from mi_voldis.fit.schedule import VIEW_STEP_COST, cost_ahead, plan_cost
    grey = FitConfig().for_backend("llvm").replace(sh_color="grey", sh_view_from=0.5)
    k = VIEW_STEP_COST
    assert degree_cost_scale(grey, 1) == pytest.approx(0.5 + 0.5 * k)
    assert degree_cost_scale(grey, 1, 0.1) == pytest.approx((0.4 + 0.5 * k) / 0.9)
    assert degree_cost_scale(grey, 1, 0.6) == degree_cost_scale(grey.replace(sh_view_from=0.0), 1) == k
    assert degree_cost_scale(grey, 0) == degree_cost_scale(grey, "auto") == 1.0
    assert degree_cost_scale(grey.replace(sh_view_resolution=None), 1) == 2.0  # harmonics at every vertex
    assert degree_cost_scale(grey.replace(sh_color="rgb"), 1) == 4.0
    cfg = grey.replace(resolution=256, min_steps=0)
    samples = 0.01 * cfg.reference_msps * 1e6
    zero = planned(cfg.replace(sh_degree=0), calibrated(0.01, samples))
    one = planned(cfg.replace(sh_degree=1), calibrated(0.01, samples))
    assert "kernel_scale" not in zero.plan and one.plan["kernel_scale"] == pytest.approx(0.5 + 0.5 * k)
    assert "kernel_scale" not in planned(cfg.replace(sh_degree=1, sh_view_resolution=None),
                                         calibrated(0.01, samples)).plan  # as before: costed at degree 0
    assert [r for _, r in one.schedule] == [r for _, r in zero.schedule]
    assert one.steps_full == pytest.approx(zero.steps_full / (0.5 + 0.5 * k), rel=2e-3)
    _, state, before = degree_one_at_step_300(grey)
    assert state.plan["kernel_scale"] == pytest.approx((0.4 + 0.5 * k) / 0.9)
    assert cost_ahead(state.schedule, state.steps_full, 300, plan_cost(state.plan, 64)) == pytest.approx(before,
                                                                                                         rel=2e-3)


def test_a_step_of_more_voxels_costs_the_samples_share_less_on_the_finer_stages():
    """step_factor: the samples' share SAMPLE_SHARE of a half-voxel step scales with 0.5 / step, the rest
    (the vertices' work) does not; StepCost.marching applies it to the stages finer than the coarse one."""
    from mi_voldis.fit.schedule import SAMPLE_SHARE, step_factor
    assert step_factor(0.5) == 1.0
    assert step_factor(1.0) == pytest.approx(1.0 - SAMPLE_SHARE / 2)
    assert step_factor(0.25) == pytest.approx(1.0 + SAMPLE_SHARE)
    base = StepCost(0.01, 64, host=0.002)
    whole = base.marching(1.0)
    assert whole.at(64) == base.at(64)  # the coarse stage marches half a voxel whatever the plan
    assert whole.at([128, 512]) == pytest.approx(0.002 + (base.at([128, 512]) - 0.002) * step_factor(1.0))
    assert StepCost.timed(0.01, 64).fine == 1.0


def test_the_step_reads_memory_as_binding_at_the_typical_vertex_count_not_the_plans_lowest():
    """choose_step: memory binds where the grid its estimate at TYPICAL_VERTICES_PER_SURFACE_CELL allows is
    no finer than the observations' (a whole voxel), even where the plan's lower count allows a finer one;
    the estimate scales as 1 / sqrt(vertices a cell) (surfaces grow as R^2)."""
    from mi_voldis.fit.schedule import (
        HALF_VOXEL,
        TYPICAL_VERTICES_PER_SURFACE_CELL,
        VERTICES_PER_SURFACE_CELL,
        WHOLE_VOXEL,
        choose_step,
        memory_resolution,
        resolution_bounds,
    )
    survey = dict(SURVEY, surface_cells=200.0)
    cfg = FitConfig().for_backend("llvm").replace(min_steps=0)
    pixels, budget = 4 * 100 * 100, 30.0
    half = default_step(cfg)
    whole = half.marching(WHOLE_VOXEL)
    seen = {}
    for gib in np.geomspace(0.45, 3.0, 300):
        c = cfg.replace(max_memory_gib=float(gib))
        bounds = resolution_bounds(c, whole, budget, survey, pixels)
        typical = memory_resolution(c, 200.0, 64, 64, c.sh_degree, pixels, per_cell=TYPICAL_VERTICES_PER_SURFACE_CELL)
        assert bounds["pixels"] > bounds["observations"]  # memory and observations decide here
        case = ("typical binds" if typical <= bounds["observations"] else "neither") + (
            ", lowest does not" if bounds["memory"] > bounds["observations"] else "")
        seen.setdefault(case, choose_step(c, half, budget, survey, pixels))
    assert seen == {"typical binds": WHOLE_VOXEL, "typical binds, lowest does not": WHOLE_VOXEL,
                    "neither, lowest does not": HALF_VOXEL}
    c = cfg.replace(max_memory_gib=2.0)
    lowest = memory_resolution(c, 2000.0, 64, 64, 0, pixels)
    quarter = memory_resolution(c, 2000.0, 64, 64, 0, pixels, per_cell=4 * VERTICES_PER_SURFACE_CELL)
    assert lowest > 128 and abs(quarter - lowest / 2) < 16


def test_the_step_is_a_whole_voxel_where_memory_not_the_budget_bounds_the_grid(monkeypatch):
    """step_voxels 'auto': costed at a whole voxel, a plan whose grid memory bounds keeps that grid and
    buys more steps on it; one whose grid the budget's observations bound keeps half a voxel and the plan
    it had (a cheaper step would only buy a finer grid, seen less); a number is the step of every stage."""
    import mi_voldis.fit.train as train
    from mi_voldis.fit.fields import step_voxels
    from mi_voldis.fit.schedule import HALF_VOXEL, WHOLE_VOXEL, choose_step, plan_cost, resolution_bounds
    survey = dict(SURVEY, surface_cells=200.0)  # a small surface: the 40,000 pixels are no bound below 848
    monkeypatch.setattr(train, "capture_survey", lambda *a: survey)
    cfg = FitConfig().for_backend("llvm").replace(min_steps=0)
    samples = 0.01 * cfg.reference_msps * 1e6  # 0.01 s a coarse step at the reference speed
    pixels = 4 * 100 * 100
    tight = planned(cfg.replace(max_memory_gib=0.6), calibrated(0.01, samples))  # memory bounds the grid
    loose = planned(cfg.replace(max_memory_gib=1e4), calibrated(0.01, samples))  # the budget does
    budget = tight.plan["budget_seconds"] - cfg.calibration_steps * 0.01
    half = default_step(cfg)
    whole = half.marching(WHOLE_VOXEL)
    assert tight.plan["step_voxels"] == WHOLE_VOXEL and loose.plan["step_voxels"] == HALF_VOXEL
    assert choose_step(cfg.replace(max_memory_gib=0.6), half, budget, survey, pixels) == WHOLE_VOXEL
    # memory-bound: the grid the half-voxel plan would have picked, more steps on it
    bounds = resolution_bounds(cfg.replace(max_memory_gib=0.6), half, budget, survey, pixels)
    assert tight.plan["final_resolution"] == bounds["memory"] < bounds["observations"]
    final = stages(cfg, 64, tight.plan["final_resolution"])
    assert tight.steps_full == steps_for(final, whole, budget) > steps_for(final, half, budget)
    assert plan_cost(tight.plan, 64).at(512) == pytest.approx(whole.at(512))
    # budget-bound: the plan a half-voxel step had
    assert loose.plan["final_resolution"] == affordable_resolution(cfg.replace(max_memory_gib=1e4), half, budget,
                                                                   survey, pixels)
    assert loose.steps_full == steps_for(stages(cfg, 64, loose.plan["final_resolution"]), half, budget)
    # the step of each stage: half a voxel on the coarse one, the plan's after it; a number everywhere
    from types import SimpleNamespace
    lattice = {r: SimpleNamespace(fields={"full": SimpleNamespace(shape=(r, r, r))}, plan=tight.plan)
               for r in (64, 128)}
    assert [step_voxels(cfg, lattice[r]) for r in (64, 128)] == [HALF_VOXEL, WHOLE_VOXEL]
    assert [step_voxels(cfg.replace(step_voxels=0.7), lattice[r]) for r in (64, 128)] == [0.7, 0.7]
    explicit = planned(cfg.replace(max_memory_gib=0.6, step_voxels=0.5), calibrated(0.01, samples))
    assert "step_voxels" not in explicit.plan and explicit.steps_full == steps_for(final, half, budget)
    # a wall-clock budget, timed on the coarse stage's half-voxel steps: the steps ahead cost the plan's step
    from mi_voldis.fit.train import replan
    wall = planned(cfg.replace(max_memory_gib=0.6, minutes=1.5), calibrated(0.01, samples))
    assert wall.plan["step_voxels"] == WHOLE_VOXEL
    second = wall.schedule[1][0]
    wall.log += [{"step": s, "step_seconds": 0.01, "time": 2.0 + 0.01 * (s - 200), "samples": samples}
                 for s in range(201, second + 1)]
    left = wall.plan["budget_seconds"] - wall.log[-1]["time"]
    marched = rescale(wall.schedule, wall.steps_full, second, StepCost.timed(0.01, 64).marching(WHOLE_VOXEL), left)
    assert rescale(wall.schedule, wall.steps_full, second, StepCost.timed(0.01, 64), left)[1] < marched[1]
    replan(wall, second)
    assert (wall.schedule, wall.steps_full) == marched
