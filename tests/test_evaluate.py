"""SPIn-NeRF-style removal scores: the regions on an analytic case, and the script on a fitted run."""
import json
import os

import numpy as np
import pytest
from test_bad_inputs import _boundary, script
from test_captures import small_transforms

from mi_voldis.evaluate import score_view
from mi_voldis.metrics import dilate, psnr


def test_regions_of_an_error_patch():
    """An error delta on a 4 x 6 patch inside the mask: each region's PSNR is -10 log10 of delta^2
    times the patch's share of that region's pixels."""
    truth = np.full((40, 50, 3), 0.5, np.float32)
    mask = np.zeros((40, 50), bool)
    mask[10:20, 15:30] = True
    render = truth.copy()
    delta = 0.2
    render[12:16, 18:24] += delta
    out = score_view(render, truth, mask, dil=2)
    region = dilate(mask, 2)
    share = {"image": 24 / mask.size, "mask": 24 / region.sum(), "bbox": 24 / (14 * 19)}
    for name, s in share.items():
        assert out[f"psnr_{name}"] == pytest.approx(-10 * np.log10(delta ** 2 * s), rel=1e-6)
    assert out["ssim_image"] > out["ssim_mask"] and out["ssim_bbox"] < 1
    assert score_view(truth, truth, mask, 2)["ssim_mask"] == pytest.approx(1.0)
    calls = []
    out = score_view(render, truth, mask, 2, perceptual=lambda a, b: calls.append(a.shape) or 0.5)
    assert out["lpips_image"] is None and calls == []  # too small for AlexNet
    big = np.repeat(np.repeat(render, 2, 0), 2, 1)
    out = score_view(big, np.repeat(np.repeat(truth, 2, 0), 2, 1), np.repeat(np.repeat(mask, 2, 0), 2, 1), 2,
                     perceptual=lambda a, b: calls.append(a.shape) or 0.5)
    assert out["lpips_image"] == 0.5 and calls == [(80, 100, 3)] and out["lpips_bbox"] is None


def test_evaluate_script(tiny_run, tiny_dataset, tmp_path, capsys):
    main = script("evaluate").main
    out = str(tmp_path / "scores.json")
    assert _boundary.run(main, [tiny_run, "--out", out, "--quiet"]) == 0
    with open(out) as f:
        scores = json.load(f)
    from mi_voldis.data import load_dataset
    from mi_voldis.render.views import render_camera
    from mi_voldis.tasks.base import FittedRun
    ds = load_dataset(tiny_dataset)
    assert scores["views"] == len(ds.test) and set(scores["per_view"]) == {ds.names[v] for v in ds.test}
    v = ds.test[0]
    render = np.clip(render_camera(FittedRun(tiny_run).integrator(), ds.cameras[v], ("bg",))["bg"][0], 0, 1)
    region = dilate(ds.masks[v], int(np.ceil(0.01 * np.hypot(*ds.size))))
    assert scores["per_view"][ds.names[v]]["psnr_mask"] == pytest.approx(psnr(render, ds.backgrounds[v], region))
    capsys.readouterr()
    plain = str(tmp_path / "plain")
    os.makedirs(plain)
    small_transforms(plain)
    assert _boundary.run(main, [tiny_run, plain]) == 1
    assert "no test view has a ground-truth background" in capsys.readouterr().err


def test_held_out_means_skip_views_where_a_metric_is_undefined():
    from mi_voldis.fit.report import mean_defined
    assert mean_defined([0.5, float("nan"), 0.7]) == pytest.approx(0.6)
    assert mean_defined([float("nan"), float("nan")]) is None
