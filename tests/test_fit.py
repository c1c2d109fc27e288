"""Fitting: what a run writes, that it renders from its own scene.xml, resume after kill -9, config."""
import json
import os
import re
import subprocess
import sys

import mitsuba as mi
import numpy as np
import pytest
from conftest import ROOT, TINY_FIT
from helpers import kill_after_checkpoint

from mi_voldis.fit.config import FitConfig
from mi_voldis.io.run_folder import write_marker
from mi_voldis.render.views import render_camera


def test_run_writes_everything(tiny_run):
    for name in ("full_grid.npz", "bg_grid.npz", "scene.xml", "config.json",
                 "metrics.json", "log.json", "training.png"):
        assert os.path.isfile(os.path.join(tiny_run, name)), name
    assert not os.path.exists(os.path.join(tiny_run, "checkpoints"))  # a finished run keeps what it made, no more
    assert any(f.endswith("_fg.png") for f in os.listdir(os.path.join(tiny_run, "previews")))
    m = json.load(open(os.path.join(tiny_run, "metrics.json")))
    for key in ("psnr", "ssim", "bg_psnr", "bg_psnr_mask", "bg_ssim_mask", "fg_coverage_iou", "fg_matte_iou"):
        assert np.isfinite(m["held_out"][key]), key
    # 60 steps on 32 x 24 images: far from converged (a flat mean colour scores about 15 dB there), but learning
    curve = [r["test_psnr"] for r in json.load(open(os.path.join(tiny_run, "log.json"))) if "test_psnr" in r]
    assert len(curve) >= 3 and curve[-1] > curve[0] + 3
    assert m["sh_choice"]["degree"] in (0, 1) and m["sh_degree"] == m["sh_choice"]["degree"]
    assert m["seconds"]["phase_full"] > 0 and m["seconds"]["phase_bg"] > 0 and m["msps_mean"] > 0
    assert 0 < m["evaluated_samples_per_ray"] <= m["max_samples_per_ray"] and m["step_size"] > 0
    assert m["peak_rss_mib"] > 100  # Python + Mitsuba + the fields: the process's own peak, recorded by itself
    # a bounded dataset (an aabb) keeps its world box; carving left only some bricks
    dataset = json.load(open(os.path.join(tiny_run, "config.json")))["dataset"]
    assert dataset["format"] == "transforms" and dataset["holdout"] == 8
    ds_box = json.load(open(os.path.join(dataset["path"], "transforms.json")))["aabb"]
    assert m["space"] == "world" and np.allclose([m["box"]["lo"], m["box"]["hi"]], ds_box)
    assert json.load(open(os.path.join(tiny_run, "config.json")))["space_used"] == "world"  # 'auto' as resolved
    assert 0 < m["bricks"]["full"]["allocated"] <= m["bricks"]["full"]["of"]


def test_scene_xml_renders_the_fitted_fields(tiny_run):
    """RUN/scene.xml, loaded by Mitsuba, renders what the metrics were computed on (same fields)."""
    from mi_voldis.data import load_dataset
    from mi_voldis.export import render_channels
    scene = mi.load_file(os.path.join(tiny_run, "scene.xml"))
    cfg = json.load(open(os.path.join(tiny_run, "config.json")))
    ds = load_dataset(cfg["dataset"]["path"])
    assert len(scene.sensors()) == len(ds.test)
    direct = render_camera(scene.integrator(), ds.cameras[ds.test[0]], ("full",))["full"][0]
    m = json.load(open(os.path.join(tiny_run, "metrics.json")))
    from mi_voldis.metrics import psnr
    assert abs(psnr(np.clip(direct, 0, 1), ds.images[ds.test[0]]) - m["per_view"][0]["psnr"]) < 1e-3
    channels = render_channels(scene, 0, spp=4)
    assert channels["R"].shape == ds.size and np.isfinite(channels["full.R"]).all()


def test_the_fitted_scene_skips_voxel_cells_stops_early_and_counts_its_samples(tiny_run):
    """scene.xml carries the fitted scene's rules (occupancy cells of ``scene_occupancy_voxels`` voxels, rays
    stopped at ``scene_stop_transmittance``), metrics.json counts the samples its held-out renders evaluate,
    and those rules evaluate no more samples than fitting's (cells of ``occupancy_voxels``, stop at 1e-4; on
    this tiny unconverged fit nearly every cell is occupied and no ray turns opaque, so as many) for an image
    that differs from theirs by less than 1% RMS (PSNR between the two above 40 dB)."""
    from mi_voldis.data import load_dataset
    from mi_voldis.metrics import psnr
    from mi_voldis.scene import build_integrator
    cfg = FitConfig()
    integ = mi.load_file(os.path.join(tiny_run, "scene.xml")).integrator()
    props = integ.properties()
    side = max(integ.fields["full"].shape)
    assert props["stop_transmittance"] == cfg.scene_stop_transmittance
    assert props["occupancy_resolution"] == int(np.ceil((side - 1) / cfg.scene_occupancy_voxels))
    m = json.load(open(os.path.join(tiny_run, "metrics.json")))
    ds = load_dataset(json.load(open(os.path.join(tiny_run, "config.json")))["dataset"]["path"])
    cam = ds.cameras[ds.test[0]]
    mine = render_camera(integ, cam)  # every layer, as scored (their chains end the rays)
    assert abs(mine["evaluated"].mean() - m["per_view"][0]["samples_per_ray"]) < 1e-6
    assert m["evaluated_samples_per_ray"] == pytest.approx(np.mean([r["samples_per_ray"] for r in m["per_view"]]))
    fitting = build_integrator(integ.fields, {**props, "stop_transmittance": 1e-4, "occupancy_resolution":
                                              int(np.ceil((side - 1) / cfg.occupancy_voxels))})
    theirs = render_camera(fitting, cam)
    assert mine["evaluated"].mean() <= theirs["evaluated"].mean()
    assert psnr(np.clip(mine["full"][0], 0, 1), np.clip(theirs["full"][0], 0, 1)) > 40


def test_grey_view_dependence_fits_saves_and_renders_from_its_scene_xml(tiny_dataset, tmp_path):
    """``sh_color=grey`` at degree 1 at every vertex (``sh_view_resolution`` null): 7 channels a vertex in
    packets of 8 in the run's grids, recorded in metrics.json, and scene.xml renders what the metrics were
    computed on."""
    from mi_voldis.data import load_dataset
    from mi_voldis.metrics import psnr
    out = tmp_path / "grey"
    sets = [s for s in TINY_FIT if not s.startswith("sh_degree")] + ["sh_degree=1", "sh_color=\"grey\"",
                                                                     "sh_view_resolution=null"]
    subprocess.run(train_args(tiny_dataset, out, sets), check=True, capture_output=True)
    m = json.load(open(out / "metrics.json"))
    assert (m["sh_degree"], m["sh_color"]) == (1, "grey")
    grid = np.load(out / "full_grid.npz")
    assert grid["data"].shape[-1] == 7  # density, the mean's RGB, one coefficient for each of Y_1^-1,0,1
    assert np.abs(grid["data"][:, 4:]).max() > 0  # the view-dependent coefficients were fitted
    # the background refits its hull; where it inpainted the hole, at its mean colour (no view dependence),
    # and every other vertex keeps the full field's gloss
    bg = np.load(out / "bg_grid.npz")
    assert (bg["table"] == grid["table"]).all()
    refit = np.any(bg["data"][:, :4] != grid["data"][:, :4], axis=1)
    gloss, full_gloss = bg["data"][:, 4:], grid["data"][:, 4:]
    cleared = (gloss == 0).all(1) & (full_gloss != 0).any(1)
    assert refit.any() and cleared.any() and not cleared[~refit].any()
    assert (gloss[~cleared] == full_gloss[~cleared]).all() and np.abs(gloss[~refit]).max() > 0
    # both fields are gated by opacity (sh_gate, the default), and the scene file says so
    assert open(out / "scene.xml").read().count('<boolean name="sh_gate" value="true"/>') == 2
    scene = mi.load_file(str(out / "scene.xml"))
    ds = load_dataset(str(tiny_dataset))
    direct = render_camera(scene.integrator(), ds.cameras[ds.test[0]], ("full",))["full"][0]
    assert abs(psnr(np.clip(direct, 0, 1), ds.images[ds.test[0]]) - m["per_view"][0]["psnr"]) < 1e-3


@pytest.mark.parametrize("view_from", [0.5, 1.0])
def test_grey_view_dependence_on_a_view_lattice_fits_saves_and_renders(tiny_dataset, tmp_path, view_from):
    """``sh_color=grey`` on a view lattice: the bricks hold density and RGB (4 channels), the grid files the
    lattice as ``view``; progressive view dependence fits it from ``sh_view_from`` of the planned steps on
    (1: never, the lattice stays 0); scene.xml renders what the metrics were computed on."""
    from mi_voldis.data import load_dataset
    from mi_voldis.metrics import psnr
    out = tmp_path / "view"
    sets = [s for s in TINY_FIT if not s.startswith("sh_degree")] + [
        "sh_degree=1", "sh_color=\"grey\"", "sh_view_resolution=12", f"sh_view_from={view_from}"]
    subprocess.run(train_args(tiny_dataset, out, sets), check=True, capture_output=True)
    m = json.load(open(out / "metrics.json"))
    assert (m["sh_degree"], m["sh_color"]) == (1, "grey")
    grid, bg = np.load(out / "full_grid.npz"), np.load(out / "bg_grid.npz")
    assert grid["data"].shape[-1] == 4 and max(grid["view"].shape[:3]) == 12 and grid["view"].shape[3] == 3
    assert (np.abs(grid["view"]).max() > 0) == (view_from < 1)
    if view_from < 1:  # the background's hole is cleared of view dependence, the rest of its lattice kept
        cleared = (bg["view"] == 0).all(-1) & (grid["view"] != 0).any(-1)
        assert cleared.any() and (bg["view"][~cleared] == grid["view"][~cleared]).all()
    scene = mi.load_file(str(out / "scene.xml"))
    ds = load_dataset(str(tiny_dataset))
    direct = render_camera(scene.integrator(), ds.cameras[ds.test[0]], ("full",))["full"][0]
    assert abs(psnr(np.clip(direct, 0, 1), ds.images[ds.test[0]]) - m["per_view"][0]["psnr"]) < 1e-3


def test_peak_rss_follows_this_process_not_its_parent():
    from mi_voldis.io.run_folder import peak_rss_mib
    code = ("import numpy as np; from mi_voldis.io.run_folder import peak_rss_mib; a = np.ones(50_000_000); "
            "print(peak_rss_mib())")
    big = np.ones(250_000_000)  # 2 GB in the parent: a forked child's ru_maxrss would include it
    assert peak_rss_mib() >= big.nbytes / 2**20
    child = float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                                 cwd=ROOT).stdout)
    assert 400 * 0.9 < child < 1500  # its own 400 MB array plus the interpreter, not the parent's 2 GB


def test_bad_config_is_refused(tmp_path):
    with pytest.raises(ValueError, match="unknown setting stepz"):
        FitConfig.from_sources(None, ["stepz=3"])
    with pytest.raises(ValueError, match="name=value"):
        FitConfig.from_sources(None, ["steps_full"])
    for item, message in (("batch_tile=0", "--set batch_tile=0: batch_tile must be a number >= 1, got 0"),
                          ("batch_rays=1.5", "batch_rays must be 'auto' or a whole number >= 1, got 1.5"),
                          ("step_voxels=-1", "step_voxels must be 'auto' or a number > 0, got -1"),
                          ("lr_color=\"fast\"", "lr_color must be a number, got \"fast\"")):
        with pytest.raises(ValueError, match=re.escape(message)):
            FitConfig.from_sources(None, [item])
    bad = tmp_path / "cfg.json"
    bad.write_text('{"batch_tile": 0}')
    with pytest.raises(ValueError, match=re.escape(f"{bad}: batch_tile must be")):
        FitConfig.from_sources(str(bad))
    bad.write_text('{"batch_tile": ')
    with pytest.raises(ValueError, match=re.escape(f"{bad}: not valid JSON (Expecting value")):
        FitConfig.from_sources(str(bad))


def test_settings_round_trip_and_help(tiny_run):
    """A finished run's config.json is a valid --config (its dataset record is skipped) and gives back
    the settings it was fitted with; --help lists every setting with its default."""
    cfg = FitConfig.from_sources(os.path.join(tiny_run, "config.json"))
    assert cfg.steps_full == 60 and cfg.resolution_schedule == [[0, 12], [20, 20]]
    text = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "train.py"), "--help"], capture_output=True,
                          text=True, check=True).stdout
    for name in FitConfig.names():
        assert f"  {name} = " in text, name
    assert "steps_full = null" in text and "minutes = \"auto\"" in text


def test_train_script_errors_name_the_dataset(tmp_path):
    run = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "train.py"), str(tmp_path / "nowhere"),
                          "--out", str(tmp_path / "run")], capture_output=True, text=True)
    assert run.returncode != 0 and "nowhere" in run.stderr and "no such dataset" in run.stderr


# with learning rates per brick (lr_views): a resumed fit counts the bricks' views anew, to the same scales
RESUME_SETS = TINY_FIT + ["sh_degree=0", "checkpoint_every=5", "steps_full=80", "lr_views=1"]
# in contracted space the fit strides through thin cells: a resumed fit takes back the levels it was stepping with;
# with free_space a resumed stage keeps the free vertices its start chose from the field then
RESUME_SPACES = {"world": ["free_space=false"], "contract": ["space=contract", "free_space=false"], "free_space": []}


@pytest.fixture(scope="module")
def uninterrupted(tiny_dataset, tmp_path_factory):
    runs = {}

    def run(space):
        if space not in runs:
            runs[space] = tmp_path_factory.mktemp("resume") / "ref"
            subprocess.run(train_args(tiny_dataset, runs[space], RESUME_SETS + RESUME_SPACES[space]), check=True,
                           capture_output=True)
        return runs[space]
    return run


def train_args(dataset, out, sets):
    """One CPU thread: a fit then repeats bit for bit (with more, atomic additions land in varying order)."""
    return [sys.executable, os.path.join(ROOT, "scripts", "train.py"), dataset, "--quiet", "--out", str(out),
            "--threads", "1"] + [x for s in sets for x in ("--set", s)]


def grids(run):
    out = {}
    for role in ("full", "bg"):
        with np.load(os.path.join(run, f"{role}_grid.npz")) as f:
            out.update({f"{role}/{k}": f[k] for k in f.files})
    return out


@pytest.mark.parametrize("space,phase,step", [("world", "full", 35), ("world", "bg", 5), ("contract", "full", 35),
                                              ("free_space", "full", 35)])
def test_resume_after_kill_equals_never_stopping(tiny_dataset, uninterrupted, tmp_path, space, phase, step):
    """kill -9 a fit after a checkpoint (in the full phase past the start of empty-space skipping, or in
    the background phase; in contracted space, with the stride levels of that skipping), resume it: the
    fields equal an uninterrupted run's bit for bit (both on one thread), no step is lost or repeated, and
    the previous run directory stays whole meanwhile."""
    sets = RESUME_SETS + RESUME_SPACES[space]
    out = tmp_path / "run"
    os.makedirs(out)
    (out / "keep.txt").write_text("an earlier run")
    write_marker(str(out), "train")  # an earlier fit's output: replaced when the resumed one is complete
    proc = subprocess.Popen(train_args(tiny_dataset, out, sets), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    checkpoint = tmp_path / "run.partial" / "checkpoints" / "last.npz"
    kill_after_checkpoint(proc, checkpoint, step, phase=phase)
    assert (out / "keep.txt").exists() and not (out / "metrics.json").exists()  # old run intact
    with np.load(checkpoint) as f:  # the checkpoint resumed from holds stride levels exactly where it strides
        assert ("strides/0/cells" in f.files) == (space == "contract")
        assert ("free" in f.files) == (space == "free_space")
    run = subprocess.run(train_args(tiny_dataset, out, sets) + ["--resume"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert not (out / "keep.txt").exists() and (out / "metrics.json").exists()  # swapped in when complete
    want, got = grids(uninterrupted(space)), grids(out)
    assert sorted(want) == sorted(got)
    for key in want:
        np.testing.assert_array_equal(got[key], want[key], err_msg=key)
    log = json.load(open(out / "log.json"))
    assert [r["step"] for r in log if "psnr" in r][:80] == list(range(1, 81))  # no step lost or repeated


def test_render_script_from_dataset_cameras(tiny_run, tmp_path):
    cfg = json.load(open(os.path.join(tiny_run, "config.json")))
    run = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "render.py"),
                          os.path.join(tiny_run, "scene.xml"), "--cameras", cfg["dataset"]["path"], "--split", "test",
                          "--out", str(tmp_path / "views")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    from mi_voldis.data import load_dataset
    ds = load_dataset(cfg["dataset"]["path"])
    written = sorted(f for f in os.listdir(tmp_path / "views") if f.endswith(".exr"))
    assert written == sorted(os.path.splitext(ds.names[v])[0] + ".exr" for v in ds.test)


@pytest.mark.parametrize("item, message", [
    ("resolution_schedule=[[0,0]]", "resolution_schedule must be null or a non-empty list of [step, vertices] pairs"),
    ("resolution_schedule=[]", "resolution_schedule must be"),
    ("resolution_schedule=[[5,32]]", "the first at step 0"),
    ("resolution_schedule=[[0,32],[10,8],[10,16]]", "steps increasing"),
    ("lr_final_ratio=-1", "lr_final_ratio must be a number > 0 and <= 1, got -1"),
    ("density_init_alpha=0", "density_init_alpha must be a number > 0"),
    ("steps_bg=-5", "steps_bg must be a number >= 0, got -5"),
    ("hull_min_views=2", "hull_min_views must be a number > 0 and <= 1, got 2"),
    ("object_alpha=-1", "object_alpha must be"),
    ("occupancy_voxels=0", "occupancy_voxels must be a number >= 1"),
    ("carve_weight=2", "carve_weight must be a number > 0 and <= 1, got 2"),
    ("space=\"nowhere\"", 'space must be one of "auto", "contract", "world", "ndc"'),
    ("distortion=-0.1", "distortion must be a number >= 0"),
    ("lr_views=-1", "lr_views must be a number >= 0, got -1"),
    ("lr_views_quantile=0", "lr_views_quantile must be a number > 0 and <= 1, got 0"),
    ("sh_degree=2", 'sh_degree must be one of "auto", 0, 1, got 2'),
    ("bg_strategy=\"magic\"", 'bg_strategy must be one of "lift", "clear", "harmonic", "guided", "scratch"'),
])
def test_settings_are_validated_where_they_are_defined(item, message):
    with pytest.raises(ValueError, match=re.escape(f"--set {item}: ") + ".*" + re.escape(message)):
        FitConfig.from_sources(None, [item])


def test_config_file_must_hold_an_object(tmp_path):
    path = tmp_path / "list.json"
    path.write_text("[1, 2]")
    with pytest.raises(ValueError, match=re.escape(f"{path}: settings must be a JSON object")):
        FitConfig.from_sources(str(path))
