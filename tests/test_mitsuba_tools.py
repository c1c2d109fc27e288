"""Mitsuba's own tools on what the scripts write: a run's scene.xml states what ``mi.render`` gives (the
integrator's raw sums) and how they become the EXR layers, and the ``.vol`` export is a complete scene
that Mitsuba's Python API and its ``mitsuba`` command render in seconds."""
import os
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_voldis.compositing import composite_channels
from mi_voldis.io.exr import read_exr
from mi_voldis.io.scene_xml import ABOUT

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_mi_render_of_a_run_scene_is_what_its_comment_states(tiny_run, tmp_path):
    """``mi.render(mi.load_file(RUN/scene.xml))``: channels 0-2 the main layer's display-encoded sums, then
    the integrator's AOVs, in the order the comment names; those, composited, are the EXR the render
    command writes (read back from the file), and differ from it as the comment says."""
    path = os.path.join(tiny_run, "scene.xml")
    text = open(path).read()
    assert ABOUT in text and "mi.render(scene)" in text and "voldis-render SCENE.xml" in text
    ET.parse(path)  # the comment keeps the file well-formed XML
    scene = mi.load_file(path)
    with dr.suspend_grad():
        image = np.array(mi.render(scene), np.float32)
    names = ["R", "G", "B"] + scene.integrator().aov_names()
    assert names[3:6] == ["A", "depth.Z", "full.R"] and names[-1] == "fg.coverage" and image.shape[2] == len(names)
    raw = {name: image[..., k] for k, name in enumerate(names)}
    from voldis_cli.render import main
    main([path, "--out", str(tmp_path / "render"), "--quiet"])
    exr = read_exr(str(tmp_path / "render" / "view000.exr"))
    expected = composite_channels(raw)
    assert sorted(exr) == sorted(expected)
    for name in expected:
        np.testing.assert_allclose(exr[name], expected[name], atol=1e-5, err_msg=name)
    # display-encoded against linear light: the raw main image is brighter wherever it is partly lit
    lit = (raw["A"] > 0.5) & (raw["R"] / np.maximum(raw["A"], 1e-6) > 0.05) & (raw["R"] < 0.95 * raw["A"])
    assert lit.sum() > 10 and np.all(raw["R"][lit] > exr["R"][lit])
    # the paper's fg is signed; the EXR's is a matte
    assert exr["fg.A"].min() >= 0.0 and raw["fg.A"].min() < 0.0


@pytest.fixture(scope="module")
def exported(tiny_run, tmp_path_factory):
    """The tiny run's full field exported by the script, as a user runs it."""
    out = tmp_path_factory.mktemp("vol") / "full"
    done = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "export_vol.py"),
                           os.path.join(tiny_run, "scene.xml"), "--out", str(out), "--resolution", "48", "--quiet"],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    return out / "full_gridvolume.xml"


def test_the_vol_export_is_a_complete_scene_from_the_runs_first_camera(exported, tiny_run):
    """It has the run's first held-out camera (pose, field of view, film) and renders with mi.render in
    a few seconds: finite, and not black where the object and table are."""
    source = ET.parse(os.path.join(tiny_run, "scene.xml")).getroot().find("sensor")
    sensor = ET.parse(exported).getroot().find("sensor")
    assert sensor is not None and ET.tostring(sensor.find("transform")) == ET.tostring(source.find("transform"))
    assert sensor.find("film").find("integer").get("value") == source.find("film").find("integer").get("value")
    scene = mi.load_file(str(exported))
    assert scene.sensors()[0].film().size().x == 32
    t = time.perf_counter()
    image = np.array(mi.render(scene))
    seconds = time.perf_counter() - t
    assert np.all(np.isfinite(image)) and image.shape[:2] == (24, 32)
    assert (image.max(axis=-1) > 0.05).mean() > 0.5, "mostly black"
    assert seconds < 60, f"the export's own sensor took {seconds:.0f} s to render 32 x 24"


@pytest.mark.skipif(shutil.which("mitsuba", path=os.path.dirname(sys.executable)) is None,
                    reason="no mitsuba command beside this Python")
def test_the_mitsuba_command_renders_the_vol_export(exported, tmp_path):
    """The export needs no Python plugin: Mitsuba's own command line renders it to an EXR."""
    command = shutil.which("mitsuba", path=os.path.dirname(sys.executable))
    out = tmp_path / "full.exr"
    done = subprocess.run([command, "-m", mi.variant(), "-o", str(out), str(exported)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    image = np.array(mi.Bitmap(str(out)))
    assert image.shape[:2] == (24, 32) and np.all(np.isfinite(image)) and image.max() > 0.05


def test_a_scene_without_sensors_exports_with_a_view_of_the_whole_region(tmp_path):
    """A source scene with no camera (one written from Python): the export gets a camera that sees the
    region, and renders with something in view."""
    from mi_voldis.field.dense_export import source_sensor, write_export
    from mi_voldis.field.spec import box_transform, field_dict
    from mi_voldis.scene import write_scene
    lo, hi = np.array([-1.0, -0.5, 0.0]), np.array([1.0, 0.5, 2.0])
    field = mi.load_dict(field_dict(np.full((3, 3, 3, 1), 2.0), np.zeros((3, 3, 3, 3)), box_transform(lo, hi)))
    (tmp_path / "run").mkdir()
    scene = write_scene(str(tmp_path / "run"), {"full": field, "bg": field}, {"samples": 8})
    assert source_sensor(scene) is None
    sigma, albedo = np.full((4, 4, 4, 1), 2.0, np.float32), np.full((4, 4, 4, 3), 0.5, np.float32)
    path = write_export(str(tmp_path / "vol"), "full", sigma, albedo, lo, hi, sensor=source_sensor(scene))
    image = np.array(mi.render(mi.load_file(path), spp=4))
    assert image.shape[:2] == (120, 160) and np.all(np.isfinite(image))
    centre, corner = image[50:70, 70:90].mean(), image[:5, :5].mean()
    assert abs(centre - corner) > 0.05, "the region is not in view"
