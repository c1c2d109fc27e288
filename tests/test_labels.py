"""Captions a reader sees: training.png's held-out curve says which views it scores (and that metrics.json
scores every test view), and a task's contact sheet names the edited result by its task."""
import os

import matplotlib

from mi_voldis import export, plots
from mi_voldis.tasks import run_task


def test_training_plot_legend_says_the_held_out_curve_scores_the_first_eval_views(tmp_path, monkeypatch):
    import matplotlib.pyplot as plt
    matplotlib.use("Agg")
    closed = []
    monkeypatch.setattr(plt, "close", closed.append)  # keep the figure to read its legends
    log = [{"phase": "full", "time": t, "loss": 1.0 / (t + 1), "psnr": 20.0 + t} for t in range(4)]
    log[-1]["test_psnr"] = 21.0  # a fit evaluates every eval_every steps, into that step's row
    plots.plot_log(str(tmp_path / "training.png"), log, "tiny")
    assert os.path.getsize(tmp_path / "training.png") > 0
    legend = [t.get_text() for t in closed[0].axes[1].get_legend().get_texts()]
    held_out = [t for t in legend if t.startswith("held-out")]
    assert held_out == [plots.HELD_OUT_LABEL]
    assert "first eval_views test views" in held_out[0] and "metrics.json: all test views" in held_out[0]


def test_a_tasks_sheet_names_its_result_by_the_task(tiny_run, tmp_path, monkeypatch):
    sheets = []
    real = export.contact_sheet

    def record(images, **kwargs):
        sheets.append(kwargs["labels"])
        return real(images, **kwargs)
    monkeypatch.setattr(export, "contact_sheet", record)
    out = run_task(tiny_run, "removal", progress=False, out=str(tmp_path / "removal"))
    assert sheets and all(labels[0] == "removal" and "image" not in labels for labels in sheets)
    assert any(name.endswith("_sheet.png") for name in os.listdir(out))
