"""The command-line programs: every one takes --quiet, the installed commands point at them, and a
long job's progress reaches a log as lines when stderr is not a terminal."""
import io
import json
import os

import numpy as np
import pytest

from mi_voldis import progress

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PROGRAMS = ("train", "optimize", "render", "make_dataset", "make_masks", "evaluate", "export_vol", "bench", "demo")


@pytest.mark.parametrize("name", PROGRAMS)
def test_every_program_takes_quiet_and_is_installed(name, capsys):
    import importlib
    module = importlib.import_module(f"voldis_cli.{name}")
    with pytest.raises(SystemExit) as exit_:
        module.main(["--help"])
    assert exit_.value.code == 0 and "--quiet" in capsys.readouterr().out
    with open(os.path.join(ROOT, "pyproject.toml")) as f:
        assert f'"voldis_cli.{name}:entry"' in f.read().split("[project.scripts]")[1]
    assert os.path.isfile(os.path.join(ROOT, "scripts", f"{name}.py"))


def test_progress_is_lines_in_a_log(monkeypatch):
    log = io.StringIO()  # not a terminal
    monkeypatch.setattr(progress, "LOG_SECONDS", 0.0)
    p = progress.Progress(4, "fit", stream=log)
    for k in range(4):
        p.set_postfix({"loss": f"{0.5 / (k + 1):.3g}"})
        p.update(1)
    p.close()
    lines = log.getvalue().splitlines()
    assert lines[0].startswith("fit: 1/4 (25%)") and "loss=0.5" in lines[0]
    assert lines[-1].startswith("fit: 4/4 (100%)") and "\r" not in log.getvalue()
    quiet = io.StringIO()
    q = progress.Progress(4, "fit", enabled=False, stream=quiet)
    q.update(4)
    q.close()
    assert quiet.getvalue() == ""


def test_a_removal_bench_row_names_its_strategy_and_the_setting_it_switches():
    """``STRATEGY``, ``STRATEGY+SETTING`` (on), ``STRATEGY-SETTING`` (off) and ``STRATEGY+SETTING=VALUE``
    rows give the refit's ``bg_strategy`` and its ``--set``; anything else is named in the error."""
    from mi_voldis.bench.run import CAPTURE_STRATEGIES, STRATEGIES, strategy_switch
    assert strategy_switch("guided") == ("guided", [])
    assert strategy_switch("guided+object_front") == ("guided", ["--set", "object_front=true"])
    assert strategy_switch("guided-object_front") == ("guided", ["--set", "object_front=false"])
    assert strategy_switch("guided+keep_seen_gap=0") == ("guided", ["--set", "keep_seen_gap=0"])
    with pytest.raises(ValueError, match="'guided-keep_seen_gap=0'"):
        strategy_switch("guided-keep_seen_gap=0")
    for row in STRATEGIES + CAPTURE_STRATEGIES:
        strategy_switch(row)
    with pytest.raises(ValueError, match="'guided object_front'"):
        strategy_switch("guided object_front")


def test_a_rerun_of_the_removal_bench_keeps_the_refits_made_since_the_fit(tmp_path, monkeypatch):
    """After an interruption the bench runs again: a strategy refitted after the scene's fit finished is
    read back, one older than the fit (or missing) is refitted."""
    from mi_voldis.bench import run as bench
    fit = tmp_path / "runs" / "scene_0"
    fit.mkdir(parents=True)
    (fit / "metrics.json").write_text("{}")
    refits = []

    def refit(args, log):
        refits.append(args[3])
        os.makedirs(args[4], exist_ok=True)
        with open(os.path.join(args[4], "metrics.json"), "w") as f:
            json.dump({"strategy": args[3]}, f)
        return 1.0
    monkeypatch.setattr(bench, "child", refit)
    rows = bench.strategy_rows(str(tmp_path), "scene", {"out": str(fit)}, ["guided", "clear"], str(tmp_path))
    assert refits == ["guided", "clear"] and rows["clear"]["wall_seconds"] == 1.0
    stale = tmp_path / "removal" / "scene" / "clear" / "metrics.json"
    fitted = os.path.getmtime(fit / "metrics.json")
    os.utime(stale, (fitted - 60, fitted - 60))
    os.utime(tmp_path / "removal" / "scene" / "guided" / "metrics.json", (fitted + 60, fitted + 60))
    refits.clear()
    rows = bench.strategy_rows(str(tmp_path), "scene", {"out": str(fit)}, ["guided", "clear"], str(tmp_path))
    assert refits == ["clear"] and rows["guided"] == {"strategy": "guided", "wall_seconds": None,
                                                      "out": str(tmp_path / "removal" / "scene" / "guided"),
                                                      "command": rows["guided"]["command"]}


def test_the_benchmark_names_each_real_capture_it_skips(tmp_path, monkeypatch, capsys):
    """Captures come from SHARED ($MI_VOLDIS_CAPTURES or ../shared/data); one that is not there is
    skipped with a line naming the folder it looked for."""
    from mi_voldis.bench import run
    (tmp_path / "statue").mkdir()
    monkeypatch.setattr(run, "SHARED", str(tmp_path))
    assert run.present(["fern", "statue", "garden"], scenes=["statue", "fern"]) == ["statue"]
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"bench: skipping fern: no {tmp_path / 'fern'} (set MI_VOLDIS_CAPTURES)"]
    # the command's check of its scenes names it; the section that then runs them does not again
    assert run.present(["fern", "statue"], ["statue", "fern"], announce=False) == ["statue"]
    assert capsys.readouterr().err == ""


def test_a_bench_with_nothing_to_run_stops_with_one_line_and_keeps_the_last_report(tmp_path, monkeypatch):
    """An unknown --scenes name, or only captures that are not there: one line, and the report folder
    (the last report) untouched."""
    from mi_voldis.bench import run
    from voldis_cli.bench import main
    monkeypatch.setattr(run, "SHARED", str(tmp_path / "none"))
    report = tmp_path / "reports"
    report.mkdir()
    (report / "removal.md").write_text("last")
    for section, scenes, message in (("--removal", "tabletop,bogus", "bogus not among"),
                                     ("--removal", "statue", "nothing to run"), ("--effects", "statue", "not among")):
        with pytest.raises(SystemExit, match=message) as stop:
            main([section, "--scenes", scenes, "--work", str(tmp_path / "work"), "--report", str(report)])
        assert str(stop.value).startswith("error: --scenes: ") and "\n" not in str(stop.value)
    assert [p.name for p in report.iterdir()] == ["removal.md"] and (report / "removal.md").read_text() == "last"
    assert not (tmp_path / "work").exists()


def test_a_bench_report_goes_only_into_a_folder_the_bench_made(tmp_path, monkeypatch):
    """--report naming a user's folder stops before any work with one line, the folder untouched; a new one
    is made and marked up front; --quick's report is not the full report's folder."""
    import voldis_cli.bench as cli
    from mi_voldis.bench import run
    from mi_voldis.io.run_folder import made_by
    notes = tmp_path / "notes"
    notes.mkdir()
    (notes / "bench.md").write_text("mine")
    with pytest.raises(SystemExit) as stop:
        cli.main(["--removal", "--scenes", "tabletop", "--work", str(tmp_path / "work"), "--report", str(notes)])
    assert str(stop.value) == (f"error: {notes}: exists and was not written by bench (no .mi-voldis naming it), "
                               "so nothing is written into it; move it away or choose another output folder")
    assert [p.name for p in notes.iterdir()] == ["bench.md"] and (notes / "bench.md").read_text() == "mine"
    assert not (tmp_path / "work").exists()
    seen = {}
    monkeypatch.setattr(run, "run_all", lambda quick, work, report, scenes: seen.update(report=report) or {})
    monkeypatch.setattr("mi_voldis.bench.report.write", lambda results, report, command: None)
    monkeypatch.chdir(tmp_path)
    cli.main(["--quick", "--quiet"])
    assert seen["report"] == "out/bench/quick" and made_by("out/bench/quick") == {"bench"}
    assert made_by(os.path.join(ROOT, "reports")) == {"bench"}  # the committed reports are the bench's


def test_the_bench_helpers_stop_with_one_line_on_a_bad_run_or_output(tmp_path):
    from mi_voldis.bench import effects, masks
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    user = tmp_path / "mine"
    user.mkdir()
    (user / "a.txt").write_text("mine")
    (tmp_path / "config.json").write_text("{}")  # tmp_path: a run's settings, so that OUT is what is refused
    for module, name in ((masks, "masks"), (effects, "effects")):
        for argv, expected in (([str(run_dir)], f"usage: python -m mi_voldis.bench.{name} RUN OUT"),
                               ([str(run_dir), str(tmp_path / "o")], f"error: {run_dir}: no config.json"),
                               ([str(tmp_path), str(user)], f"error: {user}: exists and was not written by "
                                                            f"bench_{name}")):
            with pytest.raises(SystemExit) as e:
                module.main(argv)
            assert str(e.value).startswith(expected) and "\n" not in str(e.value), (argv, str(e.value))
    assert [p.name for p in user.iterdir()] == ["a.txt"] and not (tmp_path / "o").exists()


def test_a_refit_takes_the_background_settings_of_today_and_the_rest_of_the_run(tmp_path):
    """A run fitted under older background defaults is refitted with today's (the bench and the hand
    command agree); its other settings stay, and --set still wins."""
    import json

    from mi_voldis.bench.strategies import refit_config
    from mi_voldis.fit.config import FitConfig
    today = FitConfig()
    old = {"prior_inpainter": "membrane" if today.prior_inpainter != "membrane" else "telea",
           "object_alpha": 0.5 if today.object_alpha != 0.5 else 0.4, "steps_bg": today.steps_bg + 7}
    (tmp_path / "config.json").write_text(json.dumps(old))
    cfg = refit_config(str(tmp_path), "harmonic")
    assert (cfg.bg_strategy, cfg.prior_inpainter, cfg.object_alpha) == ("harmonic", today.prior_inpainter,
                                                                          today.object_alpha)
    assert cfg.steps_bg == today.steps_bg + 7
    assert refit_config(str(tmp_path), "guided", ["object_alpha=0.3"]).object_alpha == 0.3


def test_a_refit_of_a_bad_run_or_setting_stops_with_one_line(tmp_path):
    from mi_voldis.bench.strategies import main
    out = tmp_path / "out"
    cases = [([str(tmp_path / "missing"), "guided", str(out)], "missing/config.json: cannot read settings"),
             ([str(tmp_path), "guided", str(out), "--set", "object_alpha=7"], "--set object_alpha=7: object_alpha"),
             ([str(tmp_path), "nonsense", str(out)], "bg_strategy"),
             ([str(tmp_path), "guided", str(out)], "config.json: no dataset record"),
             ([str(tmp_path)], "usage:")]
    (tmp_path / "config.json").write_text("{}")
    for argv, expected in cases:
        with pytest.raises(SystemExit) as e:
            main(argv)
        message = str(e.value)
        assert expected in message and "\n" not in message, (argv, message)
    assert not out.exists()  # nothing written


def test_effect_masks_mark_where_the_photo_differs_from_the_background_outside_the_object():
    """The bench's effect masks: a dark patch beside the object (its shadow) is found whole, noise below
    the threshold and a one-pixel difference are not, and nothing inside the object's mask is."""
    from mi_voldis.bench.effects import effect_masks
    rng = np.random.default_rng(0)
    background = rng.uniform(0.3, 0.7, (1, 40, 50, 3)).astype(np.float32)
    image = np.clip(background + rng.normal(0, 0.01, background.shape), 0, 1).astype(np.float32)
    mask = np.zeros((1, 40, 50), bool)
    mask[:, 5:20, 5:20] = True
    image[0, 5:20, 5:20] = 1.0  # the object
    image[0, 10:30, 20:35] *= 0.3  # its shadow, partly under the object's mask's edge
    image[0, 35, 45] = 0.0  # one odd pixel
    found = effect_masks(image, background, mask)
    assert not (found & mask).any() and not found[0, 33:, 40:].any()
    assert found[0, 12:28, 22:33].all()  # the shadow, but for its blurred rim
    assert found.sum() < 1.5 * 20 * 15  # a rim of a pixel or so at most
