"""Manipulation tasks on a tiny fitted run: identities, constraints, falling losses, scene.xml round trips."""
import json
import os

import mitsuba as mi
import numpy as np
import pytest

from mi_voldis.inpaint2d import has_contrib
from mi_voldis.render.views import render_camera
from mi_voldis.tasks import FittedRun, run_task


def metrics(folder):
    with open(os.path.join(folder, "metrics.json")) as f:
        return json.load(f)


def reload_and_compare(folder, integrator, layers=("composite",)):
    """The task's scene.xml renders what the in-memory edit renders."""
    run = FittedRun(os.path.dirname(folder))
    cam = run.dataset.cameras[run.dataset.test[0]]
    scene = mi.load_file(os.path.join(folder, "scene.xml"))
    a = render_camera(integrator, cam, layers)
    b = render_camera(scene.integrator(), cam, layers)
    for layer in layers:
        np.testing.assert_allclose(a[layer][0], b[layer][0], atol=1e-5)


def falling(log):
    first, last = np.mean([r["loss"] for r in log[:3]]), np.mean([r["loss"] for r in log[-3:]])
    return last < first


def test_removal_is_the_background(tiny_run):
    out = run_task(tiny_run, "removal", progress=False)
    m = metrics(out)
    assert set(m["methods"]) == {"volume", "telea", "ns"} | ({"fsr"} if has_contrib() else set())
    run = FittedRun(tiny_run)
    cam = run.dataset.cameras[run.dataset.test[0]]
    removed = render_camera(mi.load_file(os.path.join(out, "scene.xml")).integrator(), cam, ("composite", "bg"))
    ref = render_camera(run.integrator(), cam, ("bg",))
    np.testing.assert_allclose(removed["bg"][0], ref["bg"][0], atol=1e-6)
    assert mi.load_file(os.path.join(out, "scene.xml")).integrator().mode == "bg"
    assert os.path.isfile(os.path.join(out, f"view{run.dataset.test[0]:03d}.exr"))


def test_task_refers_to_the_run_and_writes_where_told(tiny_run, tmp_path):
    """--out elsewhere: the task's scene renders as the run's fields do, without a copy of them (its
    files name the run's by relative path), and no checkpoint is left unless asked for."""
    out = run_task(tiny_run, "camouflage", {"steps": 4, "checkpoint_every": 2}, progress=False,
                   out=str(tmp_path / "edits" / "camo"))
    files = os.listdir(out)
    assert not any(f.startswith(("full_", "bg_")) for f in files) and "checkpoints" not in files
    assert any(f.startswith("fg_color") for f in files)  # what the task changed is here
    text = open(os.path.join(out, "scene.xml")).read()
    assert os.path.relpath(os.path.join(tiny_run, "full_grid.npz"), out) in text
    run = FittedRun(tiny_run)
    cam = run.dataset.cameras[run.dataset.test[0]]
    scene = mi.load_file(os.path.join(out, "scene.xml"))
    np.testing.assert_allclose(render_camera(scene.integrator(), cam, ("full",))["full"][0],
                               render_camera(run.integrator(), cam, ("full",))["full"][0], atol=1e-6)
    kept = run_task(tiny_run, "camouflage", {"steps": 4, "checkpoint_every": 2}, progress=False,
                    out=str(tmp_path / "kept"), keep_checkpoints=True)
    assert os.path.isfile(os.path.join(kept, "checkpoints", "last.npz"))


def test_identity_transform_equals_the_original(tiny_run):
    out = run_task(tiny_run, "transform", {"scale": 1.0, "rotate": "y:0", "translate": [0, 0, 0],
                                           "composition": "c4"}, progress=False)
    run = FittedRun(tiny_run)
    cam = run.dataset.cameras[run.dataset.test[0]]
    moved = render_camera(mi.load_file(os.path.join(out, "scene.xml")).integrator(), cam, ("composite",))
    ref = render_camera(run.integrator(composition="c4"), cam, ("composite",))
    np.testing.assert_allclose(moved["composite"][0], ref["composite"][0], atol=1e-5)
    assert set(metrics(out)["rules_vs_ground_truth"]) == {"paper", "c2", "c3", "c4", "density"}


def test_transform_against_ground_truth_table(tiny_run):
    out = run_task(tiny_run, "transform", {"use_dataset_transform": True}, progress=False)
    m = metrics(out)
    assert m["ground_truth"] and all(np.isfinite(v["psnr"]) for v in m["rules_vs_ground_truth"].values())
    run = FittedRun(tiny_run)
    edited = run.integrator(composition="paper", fg_to_world=mi.ScalarTransform4f(
        np.asarray(m["matrix"], np.float32)))
    reload_and_compare(out, edited)


def test_camouflage_keeps_depth_and_approaches_background(tiny_run):
    out = run_task(tiny_run, "camouflage", {"steps": 30}, progress=False)
    m = metrics(out)
    assert m["max_depth_change"] == 0.0  # foreground weights fixed: depth unchanged by construction
    assert np.isfinite(m["psnr_to_background_after"]) and np.isfinite(m["psnr_to_background_before"])
    assert falling(json.load(open(os.path.join(out, "log.json"))))  # (the tiny fit has little object to hide)
    scene = mi.load_file(os.path.join(out, "scene.xml"))
    assert "fg_color" in scene.integrator().fields
    run = FittedRun(tiny_run)
    reload_and_compare(out, run.integrator(fields={"fg_color": scene.integrator().fields["fg_color"]}))


def test_nonneg_residual_only_adds_light(tiny_run):
    out = run_task(tiny_run, "nonneg", {"steps": 30}, progress=False)
    m = metrics(out)
    assert m["min_residual"] >= 0.0
    assert falling(json.load(open(os.path.join(out, "log.json"))))
    scene = mi.load_file(os.path.join(out, "scene.xml"))
    res = scene.integrator().fields["residual"]
    import mi_voldis.field.activations as act
    colour = np.array(act.sigmoid(mi.Float(np.array(res.color).ravel())))
    assert colour.min() >= 0.0  # sigmoid colours and softplus densities: non-negative by construction
    run = FittedRun(tiny_run)
    reload_and_compare(out, run.integrator(fields={"residual": res}, mode="full"), ("full", "res"))
    # its EXRs add the res layer as Blender and Nuke read it: an RGBA pass res and a Z pass res_depth
    from test_compositing import exr_passes

    from mi_voldis.io.exr import read_exr
    exrs = sorted(f for f in os.listdir(out) if f.endswith(".exr"))
    assert exrs
    nuke, blender = exr_passes(read_exr(os.path.join(out, exrs[0])))
    rgba, z = {"R", "G", "B", "A"}, {"Z"}
    assert nuke == {"rgba": rgba, "full": rgba, "bg": rgba, "fg": rgba, "res": rgba, "depth": z,
                    "full_depth": z, "bg_depth": z, "fg_depth": z, "res_depth": z}
    assert blender == {("", "Combined"): rgba, ("", "res"): rgba, ("", "res_depth"): z,
                       **{("", k): v for k, v in nuke.items() if k not in ("rgba", "res", "res_depth")}}


def test_unknown_task_and_missing_run(tiny_run, tmp_path):
    with pytest.raises(ValueError, match="unknown task"):
        run_task(tiny_run, "explode")
    with pytest.raises(ValueError, match="not a fitted run"):
        run_task(str(tmp_path), "removal")
    with pytest.raises(ValueError, match="--prompt"):
        run_task(tiny_run, "semantic", progress=False)
    before = sorted(os.listdir(tiny_run))
    for key in ("steps", "checkpoint_every"):
        with pytest.raises(ValueError, match=f"{key} must be a number >= 1, got 0"):
            run_task(tiny_run, "camouflage", {key: 0}, progress=False)
    assert sorted(os.listdir(tiny_run)) == before  # refused before anything was written


def test_task_resumes_after_kill(tiny_run, tmp_path):
    """kill -9 a camouflage run after a checkpoint, resume it: every step is done exactly once, the
    result equals an uninterrupted run's bit for bit (both on one thread), and the earlier output stays
    whole until the new one is."""
    import shutil
    import subprocess
    import sys

    from conftest import ROOT
    from helpers import kill_after_checkpoint

    from mi_voldis.io.run_folder import write_marker
    runs = {name: tmp_path / name for name in ("ref", "killed")}
    for path in runs.values():
        shutil.copytree(tiny_run, path, ignore=shutil.ignore_patterns("camouflage*"))
    args = [sys.executable, os.path.join(ROOT, "scripts", "optimize.py"), "--task", "camouflage", "--quiet",
            "--steps", "60", "--checkpoint-every", "5", "--threads", "1"]
    subprocess.run(args + [str(runs["ref"])], check=True, capture_output=True)
    os.makedirs(runs["killed"] / "camouflage")
    (runs["killed"] / "camouflage" / "keep.txt").write_text("an earlier result")
    write_marker(str(runs["killed"] / "camouflage"), "optimize")  # an earlier task's output: replaced when done
    proc = subprocess.Popen(args + [str(runs["killed"])], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    kill_after_checkpoint(proc, runs["killed"] / "camouflage.partial" / "checkpoints" / "last.npz", 10)
    assert (runs["killed"] / "camouflage" / "keep.txt").exists()
    # the run's files are compared by content: a changed scene is another job, the same bytes with a new time
    # (a run folder copied or restored) are not
    scene = runs["killed"] / "scene.xml"
    original = scene.read_bytes()
    scene.write_bytes(original + b"\n")
    refused = subprocess.run(args + [str(runs["killed"]), "--resume"], capture_output=True, text=True)
    assert refused.returncode == 1 and refused.stderr.startswith("error: "), refused.stderr
    assert "another job than the one staged (run_files.scene.xml: [" in refused.stderr
    scene.write_bytes(original)
    os.utime(scene, ns=(0, 0))
    done = subprocess.run(args + [str(runs["killed"]), "--resume"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    out = runs["killed"] / "camouflage"
    assert not (out / "keep.txt").exists() and (out / "metrics.json").exists()
    assert [r["step"] for r in json.load(open(out / "log.json"))] == list(range(1, 61))
    a = metrics(runs["ref"] / "camouflage")["psnr_to_background_after"]
    b = metrics(out)["psnr_to_background_after"]
    assert a == b, (a, b)
    volumes = sorted(f for f in os.listdir(out) if f.endswith((".vol", ".npz")))
    ref = runs["ref"] / "camouflage"
    assert volumes and volumes == sorted(f for f in os.listdir(ref) if f.endswith((".vol", ".npz")))
    for name in volumes:  # the edited fields equal an uninterrupted run's
        for got, want in zip(arrays(out / name), arrays(ref / name)):
            np.testing.assert_array_equal(got, want, err_msg=name)
    assert falling(json.load(open(out / "log.json")))


def arrays(path):
    from mi_voldis.io.vol import read_vol
    if str(path).endswith(".vol"):
        return [read_vol(str(path))]
    with np.load(path) as f:
        return [f[k] for k in sorted(f.files)]


def test_task_settings_from_the_command_line(tiny_run, tmp_path):
    """optimize.py: --set overrides a task setting, the task writes its settings to config.json, that
    file is accepted again by --config, bad values are refused naming the key, and --help lists every
    setting of every task with its default."""
    import subprocess
    import sys

    from conftest import ROOT

    from mi_voldis.tasks.settings import SETTINGS
    script = [sys.executable, os.path.join(ROOT, "scripts", "optimize.py")]
    done = subprocess.run(script + [tiny_run, "--task", "camouflage", "--quiet", "--set", "steps=4",
                                    "--set", "lr=0.2"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    written = json.load(open(os.path.join(tiny_run, "camouflage", "config.json")))
    assert written["steps"] == 4 and written["lr"] == 0.2 and written["task"] == "camouflage"
    assert len(json.load(open(os.path.join(tiny_run, "camouflage", "log.json")))) == 4
    from mi_voldis.tasks.settings import CamouflageSettings
    again = CamouflageSettings.from_sources(os.path.join(tiny_run, "camouflage", "config.json"))
    assert again.steps == 4 and again.lr == 0.2
    bad = subprocess.run(script + [tiny_run, "--task", "camouflage", "--set", "lr=-1"], capture_output=True,
                         text=True)
    assert bad.returncode == 1 and "lr must be a number > 0, got -1" in bad.stderr and "Traceback" not in bad.stderr
    text = subprocess.run(script + ["--help"], capture_output=True, text=True, check=True).stdout
    for task, cls in SETTINGS.items():
        assert f"{task} settings" in text
        for name in cls.names():
            assert f"  {name} = " in text, (task, name)


def test_readme_api_example_runs(tiny_run, tmp_path, capsys):
    """The README's Python example, on the tiny run (its path swapped in; the edit written to tmp)."""
    import re
    readme = open(os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "README.md")).read()
    code = re.search(r"<!-- api-example -->\n```python\n(.*?)```", readme, re.S).group(1)
    assert len(code.strip().splitlines()) <= 5
    code = code.replace('"out/demo/run/tabletop"', repr(tiny_run))
    moved = str(tmp_path / "moved")
    code = code.replace('run.edit("transform", {', f'run.edit("transform", out={moved!r}, settings={{')
    exec(compile(code, "README.md", "exec"), {})
    shape, task = capsys.readouterr().out.split(") ")
    assert task.strip() == "transform" and shape.startswith("(24, 32, 4")


def test_demo_picks_the_best_rule_and_renders_a_turntable(tiny_run, tmp_path, monkeypatch):
    from mi_voldis import demo
    table = {"paper": {"psnr": 17.8}, "c2": {"psnr": 19.4}, "density": {"psnr": 22.3}, "c4": {"psnr": None}}
    assert demo.best_rule({"rules_vs_ground_truth": table}) == "density"
    assert demo.best_rule({"rules_vs_ground_truth": {}}) is None
    note = demo._rule_note({"composition": "density", "rules_vs_ground_truth": table}, None)
    assert "'density'" in note and "best" in note and "22.30" in note
    run_task(tiny_run, "transform", {"use_dataset_transform": True, "composition": "density"}, progress=False)
    monkeypatch.setattr(demo, "TURNTABLE_FRAMES", 3)
    video = demo._turntable(tiny_run, str(tmp_path), "tiny")
    assert os.path.getsize(video) > 0 and video.endswith((".mp4", ".gif"))
    import imageio.v3 as iio
    frames = iio.imread(video, index=None)
    assert frames.shape[0] == 3 and frames.shape[2] >= 2 * 32  # moved beside the original
    # each panel captioned on the white band above it (demo.TURNTABLE_LABELS): dark text over both halves
    band = frames[0, :12, :, :3].min(axis=-1)
    half = frames.shape[2] // 2
    assert band[:, :half].min() < 128 and band[:, half:].min() < 128 and np.median(band) > 200
