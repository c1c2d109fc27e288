"""The benchmark's SPIn-NeRF section: the 2D baselines' scores where the answer is known, the report, the
scenes it offers, and the whole section on a tiny family scene in SPIn-NeRF's layout."""
import json
import math
import os

import numpy as np
import pytest

from mi_voldis.bench import spinnerf

GREY = np.array([102, 128, 153]) / 255  # whole 8-bit levels: OpenCV's 8-bit inpainting returns them exactly


def flat_case(background, size=(40, 50)):
    """A test photo of the flat colour GREY without the object, its mask (a 10 x 12 square), and the full
    field's render at that pose: the flat colour ``background`` with the object (red) still in the square."""
    truth = np.broadcast_to(GREY, size + (3,)).astype(np.float32)
    mask = np.zeros(size, bool)
    mask[15:25, 20:32] = True
    render = np.broadcast_to(np.asarray(background, np.float32), size + (3,)).copy()
    render[mask] = (1.0, 0.0, 0.0)
    return render, truth, mask


def test_the_2d_fill_of_a_flat_render_is_exact_and_a_wrong_render_scores_its_error():
    """Telea and Navier-Stokes fill the dilated hole of a constant image with that constant: scored against a
    photo of the same colour Navier-Stokes has no error at all (infinite PSNR) and Telea, whose weighted sums
    of 8-bit values round by up to two levels, stays above 40 dB in every region; a render whose colour is 0.2
    darker in every channel than the photo scores about -10 log10(0.2^2) = 13.98 dB in every region."""
    render, truth, mask = flat_case(GREY)
    scores = spinnerf.score_baselines({"v0": render}, {"v0": truth}, {"v0": mask}, dil=2)
    assert set(scores) == {"telea", "ns"}
    for method in ("telea", "ns"):
        mean = scores[method]["mean"]
        assert scores[method]["views"] == 1 and set(scores[method]["per_view"]) == {"v0"}
        for region in ("image", "mask", "bbox"):
            assert mean[f"psnr_{region}"] == math.inf if method == "ns" else mean[f"psnr_{region}"] > 40
        assert mean["ssim_mask"] > 0.99
    darker = GREY - 51 / 255  # 0.2 darker, still whole 8-bit levels
    wrong, _, _ = flat_case(darker)
    scores = spinnerf.score_baselines({"v0": wrong}, {"v0": truth}, {"v0": mask}, dil=2)
    for method in ("telea", "ns"):
        for region in ("image", "mask", "bbox"):
            assert scores[method]["mean"][f"psnr_{region}"] == pytest.approx(-10 * np.log10(0.2 ** 2), abs=0.1)
    # the object left in place (no fill) would score far lower in the mask: the fill did happen
    from mi_voldis.metrics import psnr
    assert psnr(render, truth, mask) < 5


def test_the_baselines_pass_lpips_through_and_average_over_views():
    render, truth, mask = flat_case(GREY, (64, 80))
    wrong, _, _ = flat_case(GREY - 51 / 255, (64, 80))
    calls = []
    scores = spinnerf.score_baselines({"a": render, "b": wrong}, {"a": truth, "b": truth}, {"a": mask, "b": mask},
                                      dil=2, perceptual=lambda x, y: calls.append(x.shape) or 0.25)
    mean = scores["telea"]["mean"]
    assert mean["lpips_image"] == 0.25 and mean["lpips_bbox"] is None  # the box is under 64 pixels a side
    assert len(calls) == 4 and all(c == (64, 80, 3) for c in calls)  # whole image of two views, two methods
    # per view, then the mean of the views' scores (the protocol's order)
    per_view = scores["telea"]["per_view"]
    assert per_view["a"]["psnr_mask"] > 40 and per_view["b"]["psnr_mask"] == pytest.approx(13.98, abs=0.1)
    assert mean["psnr_mask"] == pytest.approx((per_view["a"]["psnr_mask"] + per_view["b"]["psnr_mask"]) / 2)


def scores(image, mask, bbox):
    return {"psnr_image": image, "psnr_mask": mask, "psnr_bbox": bbox, "ssim_image": 0.9, "ssim_mask": 0.5,
            "ssim_bbox": 0.6, "lpips_image": None, "lpips_bbox": None}


def hand_results():
    """Two scenes: family10 with ours 20 dB in the mask (Telea 17, NS 18), family11 with ours 16 (Telea 17,
    NS 15): the worst is family11, -1 dB under Telea; the means are ours 18 / Telea 17 / NS 16.5."""
    def entry(kind, ours, telea, ns):
        return {"kind": kind, "half": "check", "seed": 1010, "views": 4, "train_views": 6, "dilation_px": 2,
                "size": [160, 120], "methods": {"ours": {"mean": scores(24.0, ours, ours + 1)},
                                                "telea": {"mean": scores(23.0, telea, telea + 1)},
                                                "ns": {"mean": scores(22.0, ns, ns + 1)}}}
    return {"date": "2026-11-27", "seconds": 120.0, "machine": {"cpu": "test", "cores": 2},
            "lpips": {"weights": None, "note": spinnerf.lpips_note(None)},
            "scenes": {"family10": entry("forward", 20.0, 17.0, 18.0), "family11": entry("handheld", 16.0, 17.0, 15.0)}}


def test_the_report_gives_the_mean_the_worst_scene_and_the_peers_rows_as_theirs(tmp_path):
    results = hand_results()
    s = spinnerf.summary(results)
    assert s["worst"] == "family11" and s["n"] == 2
    assert s["mean"]["ours"]["psnr_mask"] == 18.0 and s["mean"]["telea"]["psnr_mask"] == 17.0
    assert s["mean"]["ns"]["psnr_mask"] == 16.5 and s["mean"]["ours"]["lpips_image"] is None
    assert spinnerf.margin(results["scenes"]["family11"]) == -1.0
    text = open(spinnerf.write_spinnerf(results, str(tmp_path), "python scripts/bench.py --spinnerf")).read()
    assert "Worst scene: family11 (handheld rig), ours 16.00 dB in the mask, -1.00 dB over the better" in text
    assert "| mean of 2 | ours (background layer) | 24.00 | 18.00 | 19.00 |" in text
    assert "| mean of 2 | OpenCV Navier-Stokes | 22.00 | 16.50 | 17.50 |" in text
    assert "| worst: family11 | OpenCV Telea | 23.00 | 17.00 | 18.00 |" in text
    assert "| SPIn-NeRF (theirs) | published mean | 20.18 | 15.80 | - |" in text
    assert "| GScream (theirs) | published mean | 20.49 | 15.84 | - |" in text
    assert "theirs, not ours" in text and "not these scenes" in text
    assert "no LPIPS: no --lpips-weights folder given" in text
    assert "ceil(0.01 x the image diagonal) pixels (2 px at 160x120)" in text  # the protocol, stated
    assert text.index("## Mean over scenes") < text.index("## Per scene") < text.index("Protocol.")
    assert text.count("| family10 (forward, 4 test views) |") == 3  # ours, Telea, NS


def test_the_section_offers_the_family_runs_its_check_half_by_default_and_refuses_others():
    from mi_voldis.bench.run import section_scenes
    assert section_scenes("spinnerf") == [f"family{k}" for k in range(10, 24)]
    assert section_scenes("spinnerf", ["family03", "family12"]) == ["family03", "family12"]
    for other in ("random0", "tabletop", "fern"):
        with pytest.raises(ValueError, match=f"{other} not among"):
            section_scenes("spinnerf", [other])


def test_the_dataset_is_rendered_in_spinnerf_layout_once_and_the_default_layout_is_unchanged(tmp_path, monkeypatch):
    from mi_voldis.bench import run
    calls = []
    monkeypatch.setattr(run, "child", lambda args, log=None: calls.append((args, os.path.basename(log))))
    out = str(tmp_path / "family11_spinnerf")
    run.make_data("family11", out, str(tmp_path), False, layout="spinnerf")
    assert calls == [(["scripts/make_dataset.py", "--family", "11", "--out", out, "--layout", "spinnerf"],
                      "data_family11_spinnerf.log")]
    os.makedirs(out)
    open(os.path.join(out, "poses_bounds.npy"), "w").close()
    run.make_data("family11", out, str(tmp_path), False, layout="spinnerf")  # rendered: reused
    plain = str(tmp_path / "family11")
    run.make_data("family11", plain, str(tmp_path), False)
    assert len(calls) == 2 and calls[1] == (["scripts/make_dataset.py", "--family", "11", "--out", plain],
                                            "data_family11.log")


def test_bad_lpips_weights_stop_the_section_before_anything_is_rendered(tmp_path, monkeypatch):
    from voldis_cli.bench import main
    monkeypatch.setattr(spinnerf, "make_data", lambda *a, **k: pytest.fail("rendered before the weights were read"))
    with pytest.raises(ValueError, match="LPIPS"):
        spinnerf.run_spinnerf(str(tmp_path / "work"), str(tmp_path / "report"), ["family11"], str(tmp_path))
    assert not os.path.exists(tmp_path / "report")
    with pytest.raises(SystemExit):  # the flag belongs to the section
        main(["--lpips-weights", str(tmp_path), "--removal"])


TINY_SETS = ["minutes=null", "steps_full=60", "steps_bg=10", "resolution_schedule=[[0,16]]", "sh_degree=0",
             "occupancy_at_step=0", "min_steps=0"]


def test_the_section_end_to_end_on_a_tiny_family_scene(tmp_path, monkeypatch):
    """family11 rendered small in SPIn-NeRF's layout, fitted in a few dozen steps (the section's own fit, a
    child scripts/train.py, with tiny settings), scored and reported: finite whole / in-mask / box numbers
    for ours and both baselines on every test view."""
    from mi_voldis.bench import run
    from voldis_cli import make_dataset

    def tiny_data(scene, out, logs, quick, layout):
        assert layout == "spinnerf" and scene == "family11"
        make_dataset.main(["--family", "11", "--layout", "spinnerf", "--res", "32x24", "--spp", "4", "--views", "10",
                           "--out", out, "--quiet"])
        return out

    monkeypatch.setattr(spinnerf, "make_data", tiny_data)
    monkeypatch.setattr(spinnerf, "fit", lambda data, out, sets, logs: run.fit(data, out, list(sets) + TINY_SETS, logs))
    work, report = str(tmp_path / "work"), str(tmp_path / "report")
    results = spinnerf.run_spinnerf(work, report, ["family11"])
    entry = results["scenes"]["family11"]
    assert results["chosen"] == ["family11"] and results["lpips"]["weights"] is None
    assert entry["fit"]["out"] == os.path.join(work, "runs", "family11_spinnerf_0")
    assert entry["views"] == 4 and entry["train_views"] == 6 and entry["dilation_px"] == 1  # ceil(0.01 * 40)
    assert entry["size"] == [32, 24]
    for method in ("ours", "telea", "ns"):
        m = entry["methods"][method]
        assert m["views"] == 4
        for region in ("image", "mask", "bbox"):
            assert np.isfinite(m["mean"][f"psnr_{region}"]), (method, region)
        assert np.isfinite(m["mean"]["ssim_image"]) and "lpips_image" not in m["mean"]
    with open(os.path.join(report, "spinnerf.json")) as f:
        assert json.load(f)["scenes"]["family11"]["methods"]["ns"]["views"] == 4
    text = open(spinnerf.write_spinnerf(results, report, "python scripts/bench.py --spinnerf --scenes family11")).read()
    assert "Worst scene: family11" in text and "mean over 1 scene: " in text and "| mean of 1 | OpenCV Telea |" in text
    assert "(1 px at 32x24)" in text
