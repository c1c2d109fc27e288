"""What the benchmark measures of a run folder, and how it reads the removal family."""
import os

import numpy as np
import pytest

from mi_voldis.bench.run import folder_bytes


def write(path, size):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(b"\0" * size)


def test_run_folder_size_is_what_the_default_fit_leaves(tmp_path):
    run = str(tmp_path)
    write(os.path.join(run, "full_grid.npz"), 1000)
    write(os.path.join(run, "scene.xml"), 10)
    write(os.path.join(run, "previews", "view000.png"), 100)
    assert folder_bytes(run) == 1110
    # a kept checkpoint and a task folder written into the run later are not part of the fit's output
    write(os.path.join(run, "checkpoints", "last.npz"), 5000)
    write(os.path.join(run, "removal", "scene.xml"), 20)
    write(os.path.join(run, "removal", "view000.exr"), 700)
    assert folder_bytes(run) == 1110


def test_a_finished_run_is_recognised_with_its_resolved_settings(tiny_run):
    """The bench reuses a run whose config.json holds the settings asked for: 'auto' values resolved per
    backend and the records (dataset, space_used) are what a run writes, not a difference."""
    import json

    from conftest import TINY_FIT

    from mi_voldis.fit.run import finished
    dataset = json.load(open(os.path.join(tiny_run, "config.json")))["dataset"]["path"]
    assert finished(tiny_run, dataset, TINY_FIT)
    assert not finished(tiny_run, dataset, TINY_FIT + ["seed=1"])  # other settings: fitted again
    assert not finished(tiny_run, os.path.dirname(dataset), TINY_FIT)  # another dataset


def test_a_run_recorded_before_a_setting_was_added_is_still_finished(tiny_run, tmp_path):
    """A run's config.json from before a setting existed (FitConfig.ADDED) reads as the value that fitted as
    it was fitted: the bench and the strategy rows reuse it, and read back it makes the same settings."""
    import json
    import shutil

    from conftest import TINY_FIT

    from mi_voldis.bench.strategies import same_settings
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.run import finished
    old = tmp_path / "old"
    shutil.copytree(tiny_run, old)
    with open(old / "config.json") as f:
        config = json.load(f)
    dataset = config["dataset"]["path"]
    assert set(FitConfig.ADDED) <= set(config)
    # the settings it was fitted with as a run before them would have been; those whose default has
    # changed since (sh_color, hull_fill_vertical, sh_gate, sh_view_resolution, sh_view_from, fringe_contrast,
    # the fitted scene's rules, the counted last stage, the averaged iterates, the masks' free space, the
    # object's cells on the floor it stands on) read back
    # as the old value
    changed = {key for key, value in FitConfig.ADDED.items() if config[key] != value}
    assert changed == {"sh_color", "hull_fill_vertical", "sh_gate", "sh_view_resolution", "sh_view_from",
                       "fringe_contrast", "scene_occupancy_voxels", "scene_stop_transmittance", "scene_strides",
                       "strides", "sample_ns", "float_ns", "average_window", "free_space",
                       "object_behind_fill"}
    for key in FitConfig.ADDED:
        if key not in changed:
            del config[key]
    with open(old / "config.json", "w") as f:
        json.dump(config, f)
    lacking = tmp_path / "lacking.json"
    lacking.write_text(json.dumps({k: v for k, v in config.items() if k not in changed}))
    read = FitConfig.from_sources(str(lacking))
    assert read.hull_fill_vertical == 1.0 and read.sh_gate is False and read.sh_color == "rgb"
    assert read.fringe_contrast == 0.0
    assert read.scene_occupancy_voxels == read.occupancy_voxels and read.scene_stop_transmittance == 1e-4
    # the host's milliseconds it was planned with: llvm's default, not cuda's (where the suite also runs)
    assert finished(str(old), dataset, TINY_FIT + [f"host_ms={FitConfig.ADDED['host_ms']}"])
    cfg = FitConfig.from_sources(str(old / "config.json"))
    assert same_settings(str(old), cfg) and cfg.host_ms == FitConfig.ADDED["host_ms"]
    # a value other than the one it was fitted with is another fit
    assert not finished(str(old), dataset, TINY_FIT + ["host_ms=5"])


def family_results(margins, outside=None, legacy=()):
    """Removal-family results (mi_voldis.bench.family) with the default row's in-mask PSNR 20 + margin
    over Telea (20) and Navier-Stokes (19) per scene: {scene: (half, margin)}; outside the mask 30 dB, or
    20 + ``outside[scene]``. Per held-out view (0, 8, 16): the volume 20 + margin - 2, + 0, + 2, Telea 21,
    20, 19 and Navier-Stokes 19, 18.5, 19.5, so the better 2D fill of each view is 21, 20, 19.5; the scenes
    of ``legacy`` were scored before the per-view figures were kept."""
    scenes = {}
    for scene, (half, margin) in margins.items():
        methods = {"volume": {"psnr_mask": 20.0 + margin, "psnr_outside": 20.0 + (outside or {}).get(scene, 10.0),
                              "psnr_unseen": 18.0, "consistency_psnr": 30.0,
                              "fg_coverage_iou": 0.95, "bg_haze_mask": 0.02, "bg_haze_outside": 0.03,
                              "residue": 0.05, "views": [0, 8, 16],
                              "psnr_mask_views": [18.0 + margin, 20.0 + margin, 22.0 + margin]},
                   "telea": {"psnr_mask": 20.0, "consistency_psnr": 25.0, "psnr_mask_views": [21.0, 20.0, 19.0]},
                   "ns": {"psnr_mask": 19.0, "consistency_psnr": 26.5, "psnr_mask_views": [19.0, 18.5, 19.5]}}
        if scene in legacy:
            for m in methods.values():
                m.pop("views", None)
                m.pop("psnr_mask_views")
        scenes[scene] = {"half": half, "kind": "arc", "seed": 1000,
                         "strategies": {s: {"methods": methods} for s in ("guided", "guided-object_behind_fill")}}
    return {"date": "2026-11-26", "seconds": 60.0, "machine": {"cpu": "test", "cores": 2}, "scenes": scenes}


def test_the_family_report_leads_with_the_check_halfs_worst_scene_not_the_tunings():
    from mi_voldis.bench.family import lead, summary
    results = family_results({"family00": ("tuning", -3.0), "family10": ("check", 2.5), "family11": ("check", 1.5),
                              "family12": ("check", 4.0)}, outside={"family11": 1.9}, legacy=("family00",))
    check = summary(results, "guided", "check")
    assert check["worst"] == ("family11", 1.5) and check["n"] == 3
    assert check["bound"] == ["family11"]  # its background outside the mask is 1.9 dB over Telea inside it
    assert check["margins"] == [1.5, 2.5, 4.0]
    assert sorted(check["met"]) == ["family10", "family12"]  # +2 dB, +3.5 dB consistency, IoU 0.95
    assert summary(results, "guided", "tuning")["worst"] == ("family00", -3.0)
    text = "\n".join(lead(results))
    assert "check half: worst family11 +1.50 dB" in text and "2 of 3 scenes meet every target" in text
    assert "under +2 dB even outside the mask: family11; " in text
    # per view: family11 -1.50, +1.50, +4.00; family10 -0.50, +2.50, +5.00; family12 +1.00, +4.00, +6.50
    assert check["views"] == 9 and check["views_under"] == 2 and check["worst_view"] == ("family11", 0, -1.5)
    assert "held-out views under the better 2D fill of that view: 2 of 9 (worst: family11 view 0, -1.50 dB)" in text
    assert "| family11 | arc | guided | 21.50 | 18.00 | 20.00 | +1.50 | +1.90 | 1 / 3 (-1.50) | 30.00 |" in text
    assert "| family12 | arc | guided | 24.00 | 18.00 | 20.00 | +4.00 | +10.00 | 0 / 3 (+1.00) | 30.00 |" in text
    assert "| family00 | arc | guided | 17.00 | 18.00 | 20.00 | -3.00 | +10.00 | - | 30.00 |" in text  # scored before
    assert text.index("### Check half") < text.index("### Tuning half")


def test_the_family_section_offers_the_family_and_refuses_other_scenes():
    from mi_voldis.bench.run import section_scenes
    assert section_scenes("family") == [f"family{k:02d}" for k in range(24)]
    assert section_scenes("family", ["family03"]) == ["family03"]
    with pytest.raises(ValueError, match="random0 not among"):
        section_scenes("family", ["random0"])


def test_a_family_trial_fits_every_scene_with_its_settings_and_its_report_names_them(tmp_path, monkeypatch):
    """``bench.py --family --set NAME=VALUE``: every scene's fit gets the overrides (so a finished fit of
    the default is not reused for it), and the report says it is a trial, not the defaults."""
    from mi_voldis.bench import family, run
    fitted = {}
    monkeypatch.setattr(run, "make_data", lambda scene, out, logs, quick: out)
    monkeypatch.setattr(run, "fit", lambda data, out, sets, logs, keep=False: fitted.setdefault(out, sets) and {})
    monkeypatch.setattr(family, "strategy_rows", lambda *args: {})
    results = family.run_family(str(tmp_path / "work"), str(tmp_path / "report"), ["family00", "family10"],
                                sets=["tv_density=0.002"])
    assert sorted(os.path.basename(out) for out in fitted) == ["family00_0", "family10_0"]
    assert all(sets == ["tv_density=0.002"] for sets in fitted.values())
    assert results["sets"] == ["tv_density=0.002"]
    trial = family_results({"family10": ("check", 2.0)})
    assert "the default command; " in "\n".join(family.lead(trial))
    trial["sets"] = ["tv_density=0.002", "tv_color=0.0002"]
    assert ("the default command `--set tv_density=0.002` `--set tv_color=0.0002` (a trial: not the defaults)"
            in "\n".join(family.lead(trial)))


@pytest.mark.parametrize("argv, message", [
    (["--removal", "--set", "tv_density=0.002", "--report", "R"], "--set is for --family"),
    (["--family", "--set", "tv_density=0.002", "--report", os.path.abspath("reports")], "give --report DIR"),
    (["--family", "--set", "tv_density=0.002", "--report", "R", "--work", "out/bench/"], "give --work DIR"),
    (["--family", "--set", "tv_densty=0.002", "--report", "R"], "tv_densty"),
    (["--family", "--set", "tv_density=-1", "--report", "R"], "tv_density"),
])
def test_a_family_trial_refuses_bad_settings_and_the_defaults_folders_before_anything_runs(argv, message, capsys,
                                                                                           tmp_path):
    from voldis_cli.bench import main
    with pytest.raises(SystemExit) as e:
        main(["--work", str(tmp_path / "work")] + argv)
    assert e.value.code == 2 and message in capsys.readouterr().err
    assert not os.path.exists(tmp_path / "work") and not os.path.exists("R")


def test_a_family_trial_refuses_a_report_folder_that_holds_the_defaults_report(capsys, tmp_path):
    """A copy of the default's report elsewhere is not written over by a trial; a trial's own is."""
    import json

    from voldis_cli.bench import main
    report = tmp_path / "report"
    report.mkdir()
    (report / "family.json").write_text(json.dumps(family_results({"family10": ("check", 2.0)})))
    before = (report / "family.json").read_text()
    argv = ["--family", "--set", "tv_density=0.002", "--report", str(report), "--work", str(tmp_path / "work"),
            "--scenes", "family10"]
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2 and "is the default's report" in capsys.readouterr().err
    assert (report / "family.json").read_text() == before and not os.path.exists(tmp_path / "work")


def test_the_removal_report_leads_with_the_family_and_stands_alone_without_the_removal_section(tmp_path):
    import json

    from mi_voldis.bench.family import write_family
    results = family_results({"family00": ("tuning", 1.0), "family10": ("check", 2.0)})
    alone = write_family(results, str(tmp_path), "python scripts/bench.py --family")
    assert os.path.basename(alone) == "family.md" and "worst family10 +2.00 dB" in open(alone).read()
    removal = {"date": "2026-11-26", "seconds": 60.0, "machine": {"cpu": "test", "cores": 2, "variant": "llvm_ad_rgb"},
               "scenes": {}}
    (tmp_path / "removal.json").write_text(json.dumps(removal))
    text = open(write_family(results, str(tmp_path), "python scripts/bench.py --family")).read()
    assert text.startswith("# Removal by background strategy")
    assert text.index("The removal family") < text.index("The scenes the strategies were first chosen on")


def test_a_capture_without_masks_is_scored_with_the_masks_its_background_was_fitted_with(tiny_dataset, tmp_path):
    """The removal score of a run on a dataset without masks (a capture such as garden), its background
    refitted with a copy that has masks (made from a box): the background's haze in the hole and
    outside it, the residue against Telea's fill and the consistency come from the copy's masks."""
    import json
    import shutil

    from conftest import TINY_FIT

    from mi_voldis.bench.strategies import main as strategies
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.run import run_fit
    bare = tmp_path / "bare"
    shutil.copytree(tiny_dataset, bare)
    meta = json.loads((bare / "transforms.json").read_text())
    for frame in meta["frames"]:  # a capture: photos and poses, nothing else
        for key in ("object_mask_path", "coverage_path", "background_path", "moved_path"):
            frame.pop(key, None)
    (bare / "transforms.json").write_text(json.dumps(meta))
    run = str(tmp_path / "run")
    run_fit(str(bare), run, FitConfig.from_sources(None, TINY_FIT), progress=False, keep_checkpoints=True)
    out = tmp_path / "scored"
    strategies([run, "guided", str(out), str(tiny_dataset)])
    volume = json.loads((out / "metrics.json").read_text())["methods"]["volume"]
    assert volume["bg_haze_mask"] is not None and volume["bg_haze_outside"] is not None
    assert 0.0 <= volume["residue_vs_telea"] <= 1.0
    assert volume["consistency_psnr"] is not None
    assert volume["psnr_mask"] is None  # no ground-truth background to score against


def test_a_row_with_the_runs_own_settings_scores_its_background_as_a_refit_would(tiny_dataset, tmp_path):
    """The default row on a run fitted with today's defaults reuses the run's background (its seconds
    are the run's background phase); forced to refit (``--refit``, or the dataset given again) it scores
    the same."""
    import json

    from conftest import TINY_FIT

    from mi_voldis.bench.strategies import main as strategies
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.run import run_fit
    run = str(tmp_path / "run")
    run_fit(tiny_dataset, run, FitConfig.from_sources(None, TINY_FIT), progress=False, keep_checkpoints=True)
    strategies([run, "guided", str(tmp_path / "reused")])
    strategies([run, "guided", str(tmp_path / "refit"), tiny_dataset])
    strategies([run, "guided", str(tmp_path / "forced"), "--refit"])
    reused = json.loads((tmp_path / "reused" / "metrics.json").read_text())
    bg_seconds = json.loads((tmp_path / "run" / "metrics.json").read_text())["seconds"]["phase_bg"]
    assert reused["seconds"] == bg_seconds
    for name in ("refit", "forced"):
        refit = json.loads((tmp_path / name / "metrics.json").read_text())
        assert refit["seconds"] != bg_seconds
        for key in ("psnr_mask", "psnr_outside", "consistency_psnr", "bg_haze_mask"):
            assert abs(reused["methods"]["volume"][key] - refit["methods"]["volume"][key]) < 1e-3, (name, key)


def test_a_row_scores_the_background_as_the_runs_scene_renders_it_occupancy_grid_and_all(tiny_dataset, tmp_path):
    """The removal rows score what the run's scene.xml renders, whose occupancy grid skips cells (here
    every cell: this tiny fit's voxels all lie under opacity 0.1), as the run's own metrics do; the
    fields marched without the grid would score otherwise."""
    import json

    from conftest import TINY_FIT

    from mi_voldis.bench.strategies import main as strategies
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.run import run_fit
    run = str(tmp_path / "run")
    run_fit(tiny_dataset, run, FitConfig.from_sources(None, TINY_FIT + ["occupancy_alpha=0.1"]), progress=False,
            keep_checkpoints=True)
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["occupied_fraction"] < 1.0
    own = [r["bg_psnr_mask"] for r in metrics["per_view"]]
    strategies([run, "guided", str(tmp_path / "reused")])
    methods = json.loads((tmp_path / "reused" / "metrics.json").read_text())["methods"]
    assert abs(methods["volume"]["psnr_mask"] - sum(own) / len(own)) < 1e-4
    # and view by view, in the order of the run's held-out views, beside the 2D fills' own
    assert methods["volume"]["views"] == [r["view"] for r in metrics["per_view"]]
    assert np.allclose(methods["volume"]["psnr_mask_views"], own, atol=1e-4)
    for name in ("telea", "ns"):
        assert abs(np.mean(methods[name]["psnr_mask_views"]) - methods[name]["psnr_mask"]) < 1e-9


def test_a_refit_never_writes_into_its_run_its_dataset_or_a_folder_it_did_not_fill(tiny_run, tiny_dataset, tmp_path):
    """OUT as the run, inside the dataset, or a folder holding someone else's metrics.json: one line naming
    OUT and why, and every file there stays byte for byte."""
    import json
    import os

    import pytest

    from mi_voldis.bench.strategies import main as strategies
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "metrics.json").write_text(json.dumps({"psnr": 30.0}))
    cases = [(tiny_run, "is the run"), (os.path.join(tiny_dataset, "refit"), "is its dataset"),
             (str(foreign), "no background refit wrote")]
    for out, why in cases:
        watched = out if os.path.isdir(out) else os.path.dirname(out)
        before = {n: open(os.path.join(watched, n), "rb").read() for n in os.listdir(watched)
                  if os.path.isfile(os.path.join(watched, n))}
        with pytest.raises(SystemExit) as e:
            strategies([tiny_run, "guided", out])
        assert str(e.value).startswith(f"error: {out}: ") and why in str(e.value) and "\n" not in str(e.value)
        after = {n: open(os.path.join(watched, n), "rb").read() for n in os.listdir(watched)
                 if os.path.isfile(os.path.join(watched, n))}
        assert after == before and not os.path.exists(os.path.join(tiny_dataset, "refit"))
