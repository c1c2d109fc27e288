"""The command-line programs: every one takes --quiet, the installed commands point at them, and a
long job's progress reaches a log as lines when stderr is not a terminal."""
import io
import os

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


def test_a_removal_bench_row_names_its_strategy_and_the_boolean_setting_it_switches():
    """``STRATEGY``, ``STRATEGY+SETTING`` (on) and ``STRATEGY-SETTING`` (off) rows give the refit's
    ``bg_strategy`` and its ``--set``; anything else is named in the error."""
    from mi_voldis.bench.run import CAPTURE_STRATEGIES, STRATEGIES, strategy_switch
    assert strategy_switch("guided") == ("guided", [])
    assert strategy_switch("guided+object_front") == ("guided", ["--set", "object_front=true"])
    assert strategy_switch("guided-object_front") == ("guided", ["--set", "object_front=false"])
    for row in STRATEGIES + CAPTURE_STRATEGIES:
        strategy_switch(row)
    with pytest.raises(ValueError, match="'guided object_front'"):
        strategy_switch("guided object_front")
