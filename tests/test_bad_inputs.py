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

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPTS = os.path.join(ROOT, "scripts")
from mi_voldis.io.run_folder import write_marker  # noqa: E402
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
    write_marker(str(existing), "train")  # an earlier job's output: replaceable, so the case's own error shows
    for name in PROGRAMS:  # the same for each program: a job replaces only what the same program wrote
        shutil.copytree(existing, base / f"existing_{name}")
        write_marker(str(base / f"existing_{name}"), name)
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
    same = base / "same_stem"  # two views' images of one stem: view_000.png and view_000.jpg
    shutil.copytree(tiny_dataset, same)
    meta = json.load(open(same / "transforms.json"))
    import imageio.v3 as iio
    iio.imwrite(same / "images" / "view_000.jpg", iio.imread(same / meta["frames"][1]["file_path"])[..., :3])
    meta["frames"][1]["file_path"] = "images/view_000.jpg"
    json.dump(meta, open(same / "transforms.json", "w"))
    for name, breakage in (("no_config", "config"), ("bad_grid", "grid"), ("bad_xml", "xml"), ("nan_grid", "nan"),
                           ("inverted_box", "box"), ("bad_gate", "gate")):
        broken = base / name
        shutil.copytree(tiny_run, broken)
        if breakage == "config":
            os.remove(broken / "config.json")
        elif breakage == "grid":
            with open(broken / "full_grid.npz", "r+b") as f:
                f.truncate(100)
        elif breakage == "xml":
            (broken / "scene.xml").write_text((broken / "scene.xml").read_text()[:-40])
        elif breakage == "gate":  # a plugin property of the wrong type: the plugin's own message
            text = (broken / "scene.xml").read_text()
            (broken / "scene.xml").write_text(text.replace('<boolean name="sh_gate" value="true"/>',
                                                           '<string name="sh_gate" value="yes"/>', 1))
        else:
            import numpy as np
            with np.load(broken / "full_grid.npz") as f:
                arrays = {k: f[k] for k in f.files}
            if breakage == "nan":
                arrays["data"][0, 0] = np.nan
            else:  # min and max swapped on the x axis
                arrays["bbox"][:, 0] = arrays["bbox"][::-1, 0]
            np.savez(broken / "full_grid.npz", **arrays)
    (base / "plain.xml").write_text('<scene version="3.0.0"><integrator type="path"/></scene>')
    return {"dataset": tiny_dataset, "run": run, "existing": str(existing), "file": str(base / "a_file"),
            "base": str(base)}


def _p(world, text):
    """Substitute {dataset}, {run}, {existing}, {file}, {base} in a case's argument."""
    return text.format(**world)


T, OPT, R, M, E = "train", "optimize", "render", "make_dataset", "export_vol"
PROGRAMS = (T, OPT, R, M, E)
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
    (T, ["{dataset}", "--out", "{existing}", "--set", "batch_rays=1.5"], 1, "batch_rays must be 'auto' or"),
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
    (OPT, ["{run}", "--task", "transform", "--translate", "nan,0,0"], 1, "translate must be three numbers [x, y, z] of "
     "at most 1e+06 either way"),
    (OPT, ["{run}", "--task", "transform", "--translate", "1e308,0,0"], 1, "translate must be three numbers"),
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
    (OPT, ["{base}/inverted_box", "--task", "removal"], 1,
     "{base}/inverted_box/full_grid.npz: the grid's box needs min < max on every axis, got min [2.55,"),
    (OPT, ["{run}", "--task", "transform", "--rotate", "y:1e308"], 1, "--rotate: rotate must be an angle of at most "
     "1e+06 degrees either way (a turn repeats every 360), got \"y:1e308\""),
    (OPT, ["{run}", "--task", "transform", "--rotate", "1,0,0:-2e6"], 1, "--rotate: rotate must be an angle of at"),
    (OPT, ["{run}", "--task", "removal", "--seed", "-1"], 1, "--seed: seed must be a number >= 0, got -1"),
    (R, ["{base}/inverted_box/scene.xml", "--out", "{existing}"], 1,
     "{base}/inverted_box/full_grid.npz: the grid's box needs min < max on every axis"),
    (R, ["{base}/none.xml", "--out", "{existing}"], 1, "{base}/none.xml: no such scene file"),
    (R, ["{run}/scene.xml", "--cameras", "{base}/same_stem", "--split", "all", "--out", "{existing}"], 1,
     "{base}/same_stem: two views are both named 'view_000' without their extension"),
    (R, ["{base}/bad_gate/scene.xml", "--out", "{existing}"], 1,
     "{base}/bad_gate/scene.xml: full: sh_gate must be a boolean, got 'yes'"),
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
    (M, [SCENE, "--out", "{existing}", "--views", "2", "--seed", "-1"], 1, "--seed must be from 0 to 4294 for 2 "
     "views (each render's seed, seed x 1000003 + view, is a 32-bit number), got -1"),
    (M, [SCENE, "--out", "{existing}", "--views", "2", "--seed", "4295"], 1, "--seed must be from 0 to 4294 for 2"),
    (E, ["{run}/scene.xml", "--out", "{existing}", "--field", "moved"], 1, "no field 'moved'"),
    (E, ["{run}/scene.xml", "--out", "{existing}", "--region", "0,0,0,1,1"], 2, "--region expects 6"),
    (E, ["{run}/scene.xml", "--out", "{existing}", "--resolution", "0"], 2, "must be a whole number >= 1"),
]


@pytest.mark.parametrize("name,args,code,message", CASES, ids=[f"{c[0]}-{k}" for k, c in enumerate(CASES)])
def test_bad_input_is_one_line_and_leaves_outputs_alone(world, capsys, name, args, code, message):
    world = {**world, "existing": os.path.join(world["base"], f"existing_{name}")}
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


# --- Limits known before the work: with 20 GiB available (MemAvailable stood in), a render, a dataset or an
# export too large for it, or for Dr.Jit's 2^32 entries per array, is refused in one line with the estimate,
# before anything is rendered or staged.
GIB20 = "(20.0 GiB available)"
ENTRIES = "entries in one array, more than Dr.Jit's 2^32 (4,294,967,296)"
LIMIT_CASES = [
    # tiny run: 22 raw channels (RGB, film alpha, 18 AOVs) x 32 bytes per pixel
    (R, ["{run}/scene.xml", "--width", "12000", "--height", "12000"],
     f"--width/--height: a 12000x12000 render needs about 94.4 GiB {GIB20}"),
    (R, ["{run}/scene.xml", "--cameras", "{dataset}", "--width", "12000", "--height", "12000"],
     f"--width/--height: a 12000x12000 render needs about 94.4 GiB {GIB20}"),
    (R, ["{run}/scene.xml", "--path", "orbit", "--frames", "2", "--width", "12000", "--height", "12000"],
     f"--width/--height: a 12000x12000 render needs about 95.2 GiB {GIB20}"),  # + 2 kept frames of 3 bytes
    (R, ["{run}/scene.xml", "--width", "20000", "--height", "20000", "--spp", "4"],
     f"--width/--height: a 20000x20000 render (4 spp, 22 channels) needs 9,200,000,000 {ENTRIES}"),
    (R, ["{run}/scene.xml", "--width", "2000", "--height", "1000", "--spp", "4096"],
     f"--width/--height: a 2000x1000 render (4096 spp, 22 channels) needs 8,192,000,000 {ENTRIES}"),
    (M, [SCENE, "--views", "2", "--res", "12000x12000", "--spp", "1"],
     f"--res: a 12000x12000 dataset needs about 25.7 GiB {GIB20}"),  # 192 bytes per pixel
    (M, [SCENE, "--views", "2", "--res", "30000x30000", "--spp", "1"],
     f"--res: a 30000x30000 view at 1 spp needs 4,500,000,000 {ENTRIES}"),  # the film's 5 channels
    (M, [SCENE, "--views", "2", "--res", "4000x3000", "--spp", "512"],
     f"--res: a 4000x3000 view at 512 spp needs 6,144,000,000 {ENTRIES}"),
    (E, ["{run}/scene.xml", "--resolution", "2000,2000,2000"],
     f"--resolution: a 2000x2000x2000 export needs about 239.4 GiB {GIB20}"),  # 32 bytes a value + the slab
    (E, ["{run}/scene.xml", "--resolution", "70000,70000,1"],
     f"--resolution: a 70000x70000x1 export needs 4,900,000,000 {ENTRIES}"),
]


@pytest.mark.parametrize("name,args,message", LIMIT_CASES, ids=[f"{c[0]}-{k}" for k, c in enumerate(LIMIT_CASES)])
def test_too_large_a_job_is_refused_up_front_with_the_estimate(world, capsys, monkeypatch, name, args, message):
    from mi_voldis.io import limits
    monkeypatch.setattr(limits, "available_memory", lambda: 20 * limits.GIB)
    out = os.path.join(world["base"], f"limits_{name}")
    assert _boundary.run(script(name).main, [_p(world, a) for a in args] + ["--out", out, "--quiet"]) == 1
    assert capsys.readouterr().err == f"error: {message}\n"
    assert not os.path.exists(out) and not os.path.exists(out + ".partial")


def test_memory_available_is_read_from_meminfo(tmp_path):
    from mi_voldis.io import limits
    (tmp_path / "meminfo").write_text("MemTotal:       32000000 kB\nMemAvailable:   2097152 kB\n")
    assert limits.available_memory(str(tmp_path / "meminfo")) == 2 * limits.GIB
    assert limits.available_memory(str(tmp_path / "none")) is None  # not Linux: nothing refused
    (tmp_path / "old").write_text("MemTotal:       32000000 kB\n")
    assert limits.available_memory(str(tmp_path / "old")) is None


def test_an_export_region_outside_the_scene_is_refused(world, capsys):
    from mi_voldis.scene import load_scene
    field = load_scene(os.path.join(world["run"], "scene.xml")).integrator().fields["full"]
    corners = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], np.float64)
    box = corners @ field.to_world[:3, :3].T + field.to_world[:3, 3]
    lo, hi = box.min(0), box.max(0)
    out = os.path.join(world["base"], "region_out")
    beyond = f"{hi[0] + 1:g},0,0,{hi[0] + 2:g},1,1"  # past the box on x, inside on y and z
    assert _boundary.run(script(E).main, [os.path.join(world["run"], "scene.xml"), "--out", out,
                                          "--region", beyond]) == 1
    box_text = f"{','.join(f'{v:g}' for v in lo)} to {','.join(f'{v:g}' for v in hi)}"
    assert capsys.readouterr().err == (f"error: --region {beyond} lies outside the scene's box {box_text} (field "
                                       f"'full'): the export would be all zeros\n")
    assert not os.path.exists(out)
    # a region reaching into the box by a little is exported (zeros only where it lies outside)
    partly = f"{hi[0] - 0.1:g},0,0,{hi[0] + 2:g},1,1"
    assert _boundary.run(script(E).main, [os.path.join(world["run"], "scene.xml"), "--out", out, "--quiet",
                                          "--region", partly, "--resolution", "4"]) == 0
    assert os.path.isfile(os.path.join(out, "full_sigma_t.vol"))


@pytest.mark.parametrize("region,inside", [([-0.5, -0.5, 2, 0.5, 0.5, 3], True),  # in front of the camera
                                           ([-0.5, -0.5, -3, 0.5, 0.5, -2], False),  # behind it
                                           ([10, 0, 2, 11, 1, 3], False)])  # beside the frustum
def test_an_export_region_outside_an_ndc_field_is_refused(region, inside):
    from types import SimpleNamespace

    from mi_voldis.space import SceneSpace
    from voldis_cli.export_vol import check_region
    space = SceneSpace("ndc", np.eye(4), near=1.0, scale=(1.0, 1.0))
    field = SimpleNamespace(world_to_local=np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5],
                                                     [0, 0, 0, 1]]))  # NDC's [-1, 1]^3 onto the unit cube
    if inside:
        check_region(region, field, space, "full")
        return
    with pytest.raises(ValueError) as e:
        check_region(region, field, space, "full")
    assert str(e.value) == (f"--region {','.join(f'{v:g}' for v in region)} holds no point of field 'full' (its box "
                            "in NDC space): the export would be all zeros")


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


# --- Nothing a user has is lost: outputs that are, hold or lie inside an input, folders no job made,
# resumable stages, a second job on the same output. Each case is refused in one line before anything is
# written, and every input and bystander file is byte-identical afterwards.

@pytest.fixture(scope="module")
def inputs(world, tiny_dataset, tiny_run, tmp_path_factory):
    """A dataset copy inside a parent folder, a scene folder, a run copy with a task folder, masks."""
    from mi_voldis.tasks import run_task
    base = tmp_path_factory.mktemp("loss")
    parent = base / "parent"
    shutil.copytree(tiny_dataset, parent / "ds")
    scenes = base / "scenes"
    shutil.copytree(os.path.join(ROOT, "scenes"), scenes)
    run = base / "run"
    shutil.copytree(tiny_run, run)
    run_task(str(run), "transform", {"scale": 1.0}, progress=False)
    mask = base / "given.png"
    shutil.copy(os.path.join(tiny_dataset, "masks", sorted(os.listdir(os.path.join(tiny_dataset, "masks")))[0]), mask)
    return {"ds": str(parent / "ds"), "parent": str(parent), "scenes": str(scenes), "run": str(run),
            "mask": str(mask), "base": str(base)}


def _refused(name, args, message, trees, capsys):
    """Run script ``name``: exit 1 with one line holding ``message``, and ``trees`` unchanged."""
    before = {t: tree_digest(t) for t in trees}
    got = _boundary.run(script(name).main, args)
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert got == 1 and len(lines) == 1 and lines[0].startswith("error: "), err
    assert message in err, err
    assert {t: tree_digest(t) for t in trees} == before
    return err


LOSS_CASES = [  # (script, arguments, the line must contain); {ds} {parent} {scenes} {run} {mask} {dataset} (the
    # run's own) substituted
    ("train", ["{ds}", "--out", "{ds}"], "{ds}: is the dataset {ds}"),
    ("train", ["{ds}", "--out", "{parent}"], "{parent}: holds the dataset {ds}"),
    ("train", ["{ds}", "--out", "{ds}/images"], "{ds}/images: is the dataset's file {ds}/images"),
    ("make_dataset", ["{scenes}/tabletop.xml", "--out", "{scenes}"], "{scenes}: holds the scene file"),
    ("make_masks", ["{ds}", "--out", "{ds}", "--run", "{run}", "--box", "0,0,0,1,1,1"], "{ds}: is the dataset"),
    ("make_masks", ["{ds}", "--out", "{ds}/images", "--run", "{run}", "--box", "0,0,0,1,1,1"],
     "{ds}/images: is the dataset's file {ds}/images"),
    ("make_masks", ["{ds}", "--out", "{ds}/masks2", "--run", "{ds}", "--from-views", "0={mask}"],
     "{ds}: is the dataset {ds}"),
    ("make_masks", ["{ds}", "--out", "{base}/m", "--run", "{run}", "--from-views", "0={mask}", "1={base}"], "{base}"),
    ("optimize", ["{run}", "--task", "transform", "--scale", "1", "--out", "{run}"], "{run}: holds the run's file"),
    ("optimize", ["{run}", "--task", "transform", "--scale", "1", "--out", "{dataset}"], "{dataset}: is the dataset"),
    ("optimize", ["{run}", "--task", "transform", "--scale", "1", "--out", "{ds}"],
     "{ds}: holds the output of make_dataset, not of optimize, so it is not replaced"),
    ("evaluate", ["{run}", "--out", "{run}/config.json"], "{run}/config.json: is the run's file"),
    ("evaluate", ["{run}", "--out", "{dataset}/transforms.json"], "{dataset}/transforms.json: is the dataset's file"),
    ("evaluate", ["{run}", "--out", "{mask}"], "{mask}: exists and is not a score file of scripts/evaluate.py"),
    ("render", ["{run}/transform/scene.xml", "--out", "{run}/transform"], "{run}/transform: holds the scene's file"),
    ("render", ["{run}/transform/scene.xml", "--out", "{run}"], "{run}: holds the scene's file"),
    ("render", ["{run}/scene.xml", "--out", "{run}/full_grid.npz/x"], "{run}/full_grid.npz/x: lies inside"),
    ("export_vol", ["{run}/transform/scene.xml", "--out", "{run}"], "{run}: holds the scene's file"),
]


@pytest.mark.parametrize("name,args,message", LOSS_CASES, ids=[f"{c[0]}-{k}" for k, c in enumerate(LOSS_CASES)])
def test_an_output_over_an_input_is_refused_and_nothing_changes(inputs, tiny_dataset, capsys, name, args, message):
    if name == "make_masks" and "1={base}" in args:  # a given mask that is a folder: not a mask file
        message = f"{inputs['base']}: no such mask file"
    fill = {**inputs, "dataset": tiny_dataset}
    _refused(name, [a.format(**fill) for a in args], message.format(**fill), [inputs["base"], tiny_dataset], capsys)
    assert not [p for p in os.listdir(inputs["base"]) + os.listdir(inputs["run"])
                if p.endswith((".partial", ".lock", ".old"))]


def test_edit_into_its_own_run_is_refused_and_a_default_edit_never_replaces_an_earlier_one(inputs):
    import mi_voldis
    run = mi_voldis.load_run(inputs["run"])
    before = tree_digest(inputs["run"])
    with pytest.raises(ValueError, match=f"{inputs['run']}: holds the run's file"):
        run.edit("transform", {"scale": 1.0}, out=inputs["run"])
    assert tree_digest(inputs["run"]) == before
    moved = run.edit("transform", {"translate": [0.01, 0, 0]})
    try:
        assert moved.path == os.path.join(inputs["run"], "transform_2")  # RUN/transform was there already
        assert tree_digest(os.path.join(inputs["run"], "transform")) == {
            k[len("transform/"):]: v for k, v in before.items() if k.startswith("transform/")}
    finally:
        shutil.rmtree(moved.path)


@pytest.mark.parametrize("bad,message", [
    ("", "the output folder must be a path, got ''"), (".", ".: names the current folder"),
    ("..", "..: names the current folder")])
def test_an_output_naming_no_folder_is_refused_up_front(world, capsys, bad, message):
    _refused("train", [world["dataset"], "--out", bad], message, [world["base"]], capsys)


def test_folders_no_job_made_are_never_removed(world, tmp_path, capsys):
    """A user's OUT, OUT.old or OUT.partial (no marker) is neither replaced nor removed; a symbolic link
    as --out is refused, not replaced."""
    for name in ("mine", "mine.old", "mine.partial"):
        folder = tmp_path / name
        folder.mkdir()
        (folder / "notes.txt").write_text(name)
    verbs = {"mine": "replaced", "mine.old": "removed", "mine.partial": "removed"}
    for name in ("mine", "mine.old", "mine.partial"):
        out = str(tmp_path / ("mine" if name == "mine" else "other"))
        if name != "mine":
            os.rename(tmp_path / name, tmp_path / name.replace("mine", "other"))
            name = name.replace("mine", "other")
        _refused("train", [world["dataset"], "--out", out], f"{tmp_path / name}: exists and was not written by "
                 f"mi-voldis (no .mi-voldis in it), so it is not {verbs[name.replace('other', 'mine')]}",
                 [str(tmp_path), world["dataset"]], capsys)
    os.symlink(world["existing"], tmp_path / "link")
    _refused("render", [os.path.join(world["run"], "scene.xml"), "--out", str(tmp_path / "link")],
             f"{tmp_path / 'link'}: is a symbolic link (to {world['existing']})", [str(tmp_path), world["base"]],
             capsys)
    assert os.path.islink(tmp_path / "link")


@pytest.fixture
def fake_fit(monkeypatch):
    """run_fit's fit replaced by one that leaves a checkpoint and fails, as a killed fit does."""
    import mi_voldis.fit.run as fit_run

    def killed(dataset, checkpoint, cfg, resume=False, progress=True):
        os.makedirs(os.path.dirname(checkpoint), exist_ok=True)
        np_save = __import__("numpy").savez
        np_save(checkpoint, step=__import__("numpy").array(5))
        raise KeyboardInterrupt
    monkeypatch.setattr(fit_run, "fit", killed)


def test_a_resumable_stage_is_kept_until_resume_or_restart(world, tmp_path, fake_fit, capsys):
    data = str(tmp_path / "data")
    shutil.copytree(world["dataset"], data)
    out = str(tmp_path / "run")
    assert _boundary.run(script("train").main, [data, "--out", out, "--set", "steps_full=60"]) == 130
    capsys.readouterr()
    stage = out + ".partial"
    assert os.path.isfile(os.path.join(stage, "checkpoints", "last.npz"))
    kept = [str(tmp_path)]
    # a new fit without --resume, even one whose dataset then fails to load, keeps the checkpoint
    _refused("train", [data, "--out", out], f"{stage}: holds the checkpoint of an unfinished job: --resume "
             "continues it, --restart discards it", kept, capsys)
    _refused("train", [str(tmp_path / "nowhere"), "--out", out], f"{stage}: holds the checkpoint", kept, capsys)
    # --resume of another job: other settings, then a changed dataset file, named
    _refused("train", [data, "--out", out, "--resume", "--set", "steps_full=61"],
             f"{stage}: --resume of another job than the one staged (settings.steps_full: 60 -> 61)", kept, capsys)
    image = os.path.join(data, "images", sorted(os.listdir(os.path.join(data, "images")))[0])
    with open(image, "rb") as f:
        photo = f.read()
    with open(image, "wb") as f:  # one byte changed, the size kept
        f.write(photo[:-1] + bytes([photo[-1] ^ 1]))
    _refused("train", [data, "--out", out, "--resume", "--set", "steps_full=60"],
             f"dataset_files.images/{os.path.basename(image)}: [", kept, capsys)
    _refused("train", [data, "--out", out, "--resume", "--restart"], "--resume and --restart exclude each other",
             kept, capsys)
    # settings that may change do; --restart discards the stage (the fake fit then leaves a new one)
    assert _boundary.run(script("train").main, [data, "--out", out, "--restart", "--set", "steps_full=60"]) == 130
    with open(os.path.join(stage, ".mi-voldis")) as f:
        assert json.load(f)["job"]["dataset_files"][f"images/{os.path.basename(image)}"][0] == len(photo)
    assert _boundary.run(script("train").main, [data, "--out", out, "--resume", "--set", "steps_full=60",
                                                "--set", "checkpoint_every=7"]) == 130
    # the same dataset staged again (new modification times, the same bytes) is the same job
    shutil.rmtree(data)
    shutil.copytree(world["dataset"], data, copy_function=shutil.copyfile)
    with open(image, "wb") as f:
        f.write(photo[:-1] + bytes([photo[-1] ^ 1]))
    os.utime(image, ns=(0, 0))
    assert _boundary.run(script("train").main, [data, "--out", out, "--resume", "--set", "steps_full=60"]) == 130


def test_the_dataset_fingerprint_reads_regular_files_only(tmp_path):
    """A dataset folder's named pipe and dangling link are no content: fingerprinting it neither blocks
    on the pipe nor fails on the link, and its files are named by path, size and content."""
    data = tmp_path / "data"
    (data / "images").mkdir(parents=True)
    (data / "images" / "a.png").write_bytes(b"pixels")
    os.mkfifo(data / "pipe")
    os.symlink(tmp_path / "nowhere", data / "dangling")
    code = ("import json, sys; from mi_voldis.io.run_folder import fingerprint; "
            "print(json.dumps(fingerprint(sys.argv[1])))")
    done = subprocess.run([sys.executable, "-c", code, str(data)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout)
    assert list(got) == [os.path.join("images", "a.png")] and got[os.path.join("images", "a.png")][0] == 6


def test_a_second_job_on_the_same_output_is_refused(tmp_path):
    """OUT.lock holds the pid of the job writing OUT: a live one refuses a second job, a dead one's is
    taken over, and the lock goes when the job ends."""
    from mi_voldis.io.run_folder import staged
    out = str(tmp_path / "out")
    with staged(out, made_by="test"):
        with pytest.raises(ValueError, match=f"{out}: another job \\(pid {os.getpid()}\\) is writing it"):
            with staged(out, made_by="test"):
                pass
    assert not os.path.exists(out + ".lock") and os.path.isdir(out)
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    with open(out + ".lock", "w") as f:  # a user's file of that name, even one holding a dead pid, stays
        f.write(f"{dead.pid}\n")
    with pytest.raises(ValueError, match="the lock is not a mi-voldis job's"):
        with staged(out, made_by="test"):
            pass
    assert open(out + ".lock").read() == f"{dead.pid}\n"
    with open(out + ".lock", "w") as f:
        f.write(f"mi-voldis {dead.pid}\n")
    with staged(out, made_by="test") as stage:
        with open(out + ".lock") as f:
            assert f.read() == f"mi-voldis {os.getpid()}\n"
        open(os.path.join(stage, "x"), "w").close()
    assert os.path.isfile(os.path.join(out, "x")) and not os.path.exists(out + ".lock")
    with open(out + ".lock", "w") as f:
        f.write("not a pid")
    with pytest.raises(ValueError, match="not a mi-voldis job's"):
        with staged(out, made_by="test"):
            pass


def test_threads_above_the_cores_are_warned(capsys):
    import argparse
    _boundary.set_threads(argparse.Namespace(threads=(os.cpu_count() or 1) + 1))
    err = capsys.readouterr().err
    assert err.startswith(f"warning: --threads {(os.cpu_count() or 1) + 1} is more than the") and err.count("\n") == 1
    import drjit as dr
    dr.set_thread_count(os.cpu_count() or 1)
    _boundary.set_threads(argparse.Namespace(threads=1))
    assert capsys.readouterr().err == ""
    dr.set_thread_count(os.cpu_count() or 1)


@pytest.mark.parametrize("call,message", [
    (lambda run: run.render(view=1.7), "view: must be a view index (a whole number), got 1.7"),
    (lambda run: run.render(view="r_000.png"), "view: must be a view index"),
    (lambda run: run.render(view=999), "view: 999 is out of range (the dataset has 9 views)"),
    (lambda run: run.render(layers=("composite", "shadow")), "layers: unknown layer 'shadow'"),
    (lambda run: run.render(camera="front"), "camera: must be a mi_voldis.cameras.Camera"),
    (lambda run: run.edit("explode"), "task: unknown task 'explode'"),
    (lambda run: run.edit("transform", [1, 2]), "settings: must be a dict of transform settings"),
])
def test_the_api_names_the_wrong_argument(world, call, message):
    import mi_voldis
    run = mi_voldis.load_run(world["run"])
    before = tree_digest(world["run"])
    with pytest.raises(ValueError, match=message.replace("(", "\\(").replace(")", "\\)").replace(".", "\\.")):
        call(run)
    assert tree_digest(world["run"]) == before


def test_the_api_renders_one_layer_given_as_a_string(world):
    import mi_voldis
    layers = mi_voldis.load_run(world["run"]).render(view=-1, layers="fg")
    assert sorted(layers) == ["depth", "fg"] and layers["fg"].shape[-1] == 4
