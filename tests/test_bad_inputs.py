"""Bad input through the scripts, as a user gives it: one line naming the file (or flag) and the problem,
exit code 1 (2 for usage), no traceback, and every output folder that existed before byte-identical after.

Cases run the scripts' ``main`` in this process through their boundary (``voldis_cli/boundary.py``), as
``python scripts/X.py`` does, so that 50 cases cost seconds; two run as real processes as well."""
import hashlib
import importlib.util
import json
import os
import shutil
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPTS = os.path.join(ROOT, "scripts")
from voldis_cli import boundary as _boundary  # noqa: E402


def script(name):
    spec = importlib.util.spec_from_file_location(f"script_{name}", os.path.join(SCRIPTS, f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def tree_digest(path):
    """{relative path: sha256} of every file under ``path`` (empty if it does not exist)."""
    out = {}
    for d, _, files in os.walk(path):
        for f in files:
            with open(os.path.join(d, f), "rb") as fh:
                out[os.path.relpath(os.path.join(d, f), path)] = hashlib.sha256(fh.read()).hexdigest()
    return out


@pytest.fixture(scope="module")
def world(tiny_dataset, tiny_run, tmp_path_factory):
    """Paths the cases refer to: a dataset, a fitted run (copy), an existing output folder, broken files."""
    base = tmp_path_factory.mktemp("bad")
    run = str(base / "run")
    shutil.copytree(tiny_run, run)
    existing = base / "existing"
    existing.mkdir()
    (existing / "keep.txt").write_text("an earlier result")
    (base / "a_file").write_text("not a folder")
    (base / "list.json").write_text("[1, 2]")
    (base / "broken.json").write_text('{"steps_full": ')
    (base / "empty_dataset").mkdir()
    fov0 = base / "fov0"
    shutil.copytree(tiny_dataset, fov0)
    meta = json.load(open(fov0 / "transforms.json"))
    meta.pop("fl_x", None)
    meta.pop("fl_y", None)
    meta["camera_angle_x"] = 0
    json.dump(meta, open(fov0 / "transforms.json", "w"))
    for name, splits in (("alltest", lambda k: "test"), ("notest", None), ("onetrain", lambda k: "train" if k == 0
                                                                                   else "test" if k < 3 else None)):
        copy = base / name
        shutil.copytree(tiny_dataset, copy)
        meta = json.load(open(copy / "transforms.json"))
        frames = []
        for k, frame in enumerate(meta["frames"]):
            split = splits(k) if splits else None
            if split is None and splits is not None:
                continue
            frame.pop("split", None)
            if split:
                frame["split"] = split
            frames.append(frame)
        meta["frames"] = frames
        json.dump(meta, open(copy / "transforms.json", "w"))
    for name, breakage in (("no_config", "config"), ("bad_grid", "grid"), ("bad_xml", "xml"), ("nan_grid", "nan")):
        broken = base / name
        shutil.copytree(tiny_run, broken)
        if breakage == "config":
            os.remove(broken / "config.json")
        elif breakage == "grid":
            with open(broken / "full_grid.npz", "r+b") as f:
                f.truncate(100)
        elif breakage == "xml":
            (broken / "scene.xml").write_text((broken / "scene.xml").read_text()[:-40])
        else:
            import numpy as np
            with np.load(broken / "full_grid.npz") as f:
                arrays = {k: f[k] for k in f.files}
            arrays["data"][0, 0] = np.nan
            np.savez(broken / "full_grid.npz", **arrays)
    (base / "plain.xml").write_text('<scene version="3.0.0"><integrator type="path"/></scene>')
    return {"dataset": tiny_dataset, "run": run, "existing": str(existing), "file": str(base / "a_file"),
            "base": str(base)}


def _p(world, text):
    """Substitute {dataset}, {run}, {existing}, {file}, {base} in a case's argument."""
    return text.format(**world)


T, OPT, R, M, E = "train", "optimize", "render", "make_dataset", "export_vol"
SCENE = "scenes/tabletop.xml"
CASES = [
    # (script, arguments, exit code, text the one line must contain)
    (T, ["{dataset}", "--out", "{existing}", "--threads", "0"], 2, "--threads: must be a whole number >= 1"),
    (T, ["{base}/nowhere", "--out", "{existing}"], 1, "{base}/nowhere: no such dataset folder"),
    (T, ["{base}/empty_dataset", "--out", "{existing}"], 1, "neither transforms.json, poses_bounds.npy nor"),
    (T, ["{base}/fov0", "--out", "{existing}"], 1, "camera_angle_x must be in (0, pi)"),
    (T, ["{dataset}", "--out", "{existing}", "--holdout", "-2"], 2, "--holdout must be 0"),
    (T, ["{base}/alltest", "--out", "{existing}"], 1, "{base}/alltest: no training views"),
    (T, ["{dataset}", "--out", "{file}"], 1, "{file}: exists and is not a folder"),
    (T, ["{dataset}", "--out", "{file}/run"], 1, "{file}: is a file, so {file}/run cannot be made"),
    (T, ["{dataset}", "--out", "{existing}", "--resume"], 1, "nothing to resume"),
    (T, ["{dataset}", "--out", "{existing}", "--format", "nerf"], 2, "invalid choice"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "resolution_schedule=[[0,0]]"], 1, "resolution_schedule must"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "resolution_schedule=[]"], 1, "resolution_schedule must"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "lr_final_ratio=-1"], 1, "lr_final_ratio must be a number > 0"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "density_init_alpha=0"], 1, "density_init_alpha must be"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "steps_bg=-5"], 1, "steps_bg must be a number >= 0"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "hull_min_views=2"], 1, "hull_min_views must be"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "object_alpha=-1"], 1, "object_alpha must be"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "occupancy_resolution=-1"], 1, "unknown setting"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "minutes=-1"], 1, "minutes must be"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "steps_full"], 1, "name=value"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "batch_rays=1.5"], 1, "batch_rays must be a whole number"),
    (T, ["{dataset}", "--out", "{existing}", "--set", "sh_degree=3"], 1, "sh_degree must be one of"),
    (T, ["{dataset}", "--out", "{existing}", "--config", "{base}/list.json"], 1,
     "{base}/list.json: settings must be a JSON object"),
    (T, ["{dataset}", "--out", "{existing}", "--config", "{base}/broken.json"], 1,
     "{base}/broken.json: not valid JSON"),
    (T, ["{dataset}", "--out", "{existing}", "--config", "{base}/none.json"], 1, "{base}/none.json: cannot read"),
    (OPT, ["{base}/norun", "--task", "removal"], 1, "{base}/norun: no such run folder"),
    (OPT, ["{run}", "--task", "explode"], 2, "invalid choice"),
    (OPT, ["{run}", "--task", "transform", "--scale", "0"], 1, "scale must be a number >= 0.001"),
    (OPT, ["{run}", "--task", "transform", "--scale", "1e-9"], 1, "scale must be a number >= 0.001"),
    (OPT, ["{run}", "--task", "transform", "--scale", "big"], 1, "--scale expects a float"),
    (OPT, ["{run}", "--task", "transform", "--translate", "nan,0,0"], 1, "translate must be three finite numbers"),
    (OPT, ["{run}", "--task", "transform", "--translate", "1,2"], 1, "--translate expects X,Y,Z"),
    (OPT, ["{run}", "--task", "transform", "--rotate", "y:nan"], 1, "rotate must be"),
    (OPT, ["{run}", "--task", "transform", "--rotate", "q:30"], 1, "rotate must be"),
    (OPT, ["{run}", "--task", "transform", "--composition", "magic"], 1, "composition must be one of"),
    (OPT, ["{run}", "--task", "camouflage", "--steps", "0"], 1, "steps must be a number >= 1"),
    (OPT, ["{run}", "--task", "removal", "--scale", "2"], 2, "takes no --scale"),
    (OPT, ["{run}", "--task", "semantic"], 1, "--prompt"),
    (OPT, ["{base}/no_config", "--task", "removal"], 1, "{base}/no_config/config.json: cannot read"),
    (OPT, ["{base}/bad_grid", "--task", "removal"], 1, "full_grid.npz: not a brick grid file"),
    (OPT, ["{base}/nan_grid", "--task", "removal"], 1, "full_grid.npz: brick data contains NaN"),
    (OPT, ["{base}/bad_xml", "--task", "removal"], 1, "scene.xml"),
    (R, ["{base}/none.xml", "--out", "{existing}"], 1, "{base}/none.xml: no such scene file"),
    (R, ["{run}/scene.xml", "--out", "{existing}", "--spp", "-4"], 2, "--spp: must be a whole number >= 1"),
    (R, ["{run}/scene.xml", "--out", "{existing}", "--spp", "0"], 2, "--spp: must be a whole number >= 1"),
    (R, ["{run}/scene.xml", "--out", "{existing}", "--width", "0", "--height", "0"], 2, "--width: must be"),
    (R, ["{run}/scene.xml", "--out", "{existing}", "--width", "10"], 2, "--width and --height go together"),
    (R, ["{base}/plain.xml", "--out", "{existing}"], 1, "{base}/plain.xml: its integrator is not a 'voldis'"),
    (R, ["{base}/bad_xml/scene.xml", "--out", "{existing}"], 1, "{base}/bad_xml/scene.xml"),
    (R, ["{run}/scene.xml", "--out", "{file}"], 1, "{file}: exists and is not a folder"),
    (R, ["{run}/scene.xml", "--out", "{existing}", "--cameras", "{base}/nowhere"], 1, "no such dataset folder"),
    (M, [SCENE, "--out", "{existing}", "--views", "0"], 2, "--views: must be a whole number >= 1"),
    (M, [SCENE, "--out", "{existing}", "--views", "-3"], 2, "--views: must be a whole number >= 1"),
    (M, [SCENE, "--out", "{existing}", "--views", "1"], 2, "--views must be at least 2"),
    (M, [SCENE, "--out", "{existing}", "--spp", "0"], 2, "--spp: must be a whole number >= 1"),
    (M, [SCENE, "--out", "{existing}", "--holdout", "1"], 2, "--holdout must be 0"),
    (M, [SCENE, "--out", "{existing}", "--holdout", "-1"], 2, "--holdout must be 0"),
    (M, [SCENE, "--out", "{existing}", "--res", "0x10"], 2, "--res must look like"),
    (M, ["{base}/none.xml", "--out", "{existing}"], 1, "{base}/none.xml: no such scene file"),
    (M, [SCENE, "--out", "{file}", "--views", "2", "--res", "8x6", "--spp", "1"], 1, "{file}: exists and is not"),
    (E, ["{run}/scene.xml", "--out", "{existing}", "--field", "moved"], 1, "no field 'moved'"),
    (E, ["{run}/scene.xml", "--out", "{existing}", "--region", "0,0,0,1,1"], 2, "--region expects 6"),
    (E, ["{run}/scene.xml", "--out", "{existing}", "--resolution", "0"], 2, "must be a whole number >= 1"),
]


@pytest.mark.parametrize("name,args,code,message", CASES, ids=[f"{c[0]}-{k}" for k, c in enumerate(CASES)])
def test_bad_input_is_one_line_and_leaves_outputs_alone(world, capsys, name, args, code, message):
    args = [_p(world, a) for a in args]
    watched = [world["existing"], world["run"]] + [os.path.join(world["base"], n) for n in
                                                   ("no_config", "bad_grid", "bad_xml", "nan_grid")]
    before = [tree_digest(p) for p in watched]
    with open(world["file"], "rb") as f:
        file_before = f.read()
    main = script(name).main
    try:
        got = _boundary.run(main, args)
    except SystemExit as e:  # argparse usage errors
        got = e.code
    err = capsys.readouterr().err
    assert got == code, err
    assert _p(world, message) in err, err
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.strip()]
    if code == 1:
        assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert [tree_digest(p) for p in watched] == before
    with open(world["file"], "rb") as f:
        assert f.read() == file_before
    assert not os.path.exists(world["existing"] + ".partial")  # nothing was staged, or it was cleaned up


def test_as_real_processes_with_and_without_debug(world):
    args = [sys.executable, os.path.join(SCRIPTS, "optimize.py"), world["run"], "--task", "transform", "--scale", "0"]
    done = subprocess.run(args, capture_output=True, text=True)
    assert done.returncode == 1 and done.stderr.strip().count("\n") == 0 and "scale must be" in done.stderr
    debug = subprocess.run(args + ["--debug"], capture_output=True, text=True)
    assert debug.returncode == 1 and "Traceback" in debug.stderr and "scale must be" in debug.stderr
    usage = subprocess.run([sys.executable, os.path.join(SCRIPTS, "make_dataset.py"), SCENE, "--out",
                            world["existing"], "--views", "0"], capture_output=True, text=True, cwd=ROOT)
    assert usage.returncode == 2 and "Traceback" not in usage.stderr


def test_internal_errors_say_how_to_see_the_traceback(capsys):
    def broken(argv):
        raise KeyError("slot")
    assert _boundary.run(broken, []) == 1
    err = capsys.readouterr().err
    assert err.startswith("error: 'slot' (KeyError; run again with --debug") and "Traceback" not in err
    with pytest.raises(KeyError):
        _boundary.run(broken, ["--debug"])


@pytest.mark.parametrize("dataset,holdout", [("notest", "0"), ("onetrain", "8")])
def test_unusual_but_legal_datasets_fit_to_the_end(world, tmp_path, dataset, holdout):
    """No test views (holdout 0), or a single training view: the fit runs to the end and says so."""
    from conftest import TINY_FIT
    out = tmp_path / "run"
    sets = [x for s in TINY_FIT + ["steps_full=30", "steps_bg=4"] for x in ("--set", s)]
    assert _boundary.run(script("train").main, [os.path.join(world["base"], dataset), "--out", str(out), "--quiet",
                                                "--holdout", holdout] + sets) == 0
    metrics = json.load(open(out / "metrics.json"))
    tests = {"notest": 0, "onetrain": 2}[dataset]
    assert metrics["views"]["test"] == tests and metrics["views"]["train"] >= 1
    assert (metrics["held_out"] == {}) == (tests == 0)
