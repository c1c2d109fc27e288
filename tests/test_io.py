"""Round trips (.vol, EXR, XML) and clear errors for bad files and properties."""
import os
import subprocess
import sys

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import box_transform, integrator, ortho_scene, random_field

from mi_voldis.io.exr import read_exr, write_exr
from mi_voldis.io.scene_xml import save_field, sensor_xml, write_scene
from mi_voldis.io.vol import read_header, read_vol, write_vol

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_vol_round_trip(tmp_path):
    values = np.random.default_rng(0).normal(0, 10, (3, 4, 5, 12)).astype(np.float32)
    path = tmp_path / "a.vol"
    write_vol(path, values, (-1, -2, -3), (1, 2, 3))
    np.testing.assert_array_equal(read_vol(path), values)
    x, y, z, c, lo, hi = read_header(path)
    assert (x, y, z, c) == (5, 4, 3, 12)
    np.testing.assert_array_equal(lo, [-1, -2, -3])
    np.testing.assert_array_equal(hi, [1, 2, 3])


@pytest.mark.parametrize("channels", [12, 6])
def test_field_written_and_read_back_exactly(tmp_path, channels):
    """A field saved to .vol files and loaded by the plugin has bit-identical tensors and box (RGB and grey
    degree-1 harmonics)."""
    integ = integrator(random_field(1, channels=channels), random_field(2))
    full = integ.fields["full"]
    body = save_field(str(tmp_path), "full", np.array(full.density), np.array(full.color), full.to_world)
    body = body.replace('value="full_', f'value="{tmp_path}/full_')
    loaded = mi.load_string(f'<medium version="3.0.0" type="radiance_field">{body}</medium>')
    np.testing.assert_array_equal(np.array(loaded.density), np.array(full.density))
    np.testing.assert_array_equal(np.array(loaded.color), np.array(full.color))
    np.testing.assert_array_equal(loaded.to_world, full.to_world)
    # without to_world, the box comes from the .vol header
    header_only = mi.load_dict({"type": "radiance_field", "density": str(tmp_path / "full_density.vol"),
                                "color": str(tmp_path / "full_color.vol")})
    np.testing.assert_allclose(header_only.to_world, full.to_world, atol=1e-6)


def test_exr_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    channels = {name: rng.normal(0, 1, (5, 7)).astype(np.float32)
                for name in ("R", "G", "B", "A", "depth.Z", "fg.R", "fg.G", "fg.B", "fg.A", "fg.Z")}
    write_exr(tmp_path / "x.exr", dict(channels))
    back = read_exr(tmp_path / "x.exr")
    assert set(back) == set(channels)
    for name, value in channels.items():
        np.testing.assert_array_equal(back[name], value)


def scene_files(tmp_path):
    """The same scene as an XML file (fields in .vol files) and as a dict (fields as tensors)."""
    full, bg = random_field(5), random_field(6, channels=12)
    integ = integrator(full, bg, samples=16, composition="c4")
    bodies = {role: save_field(str(tmp_path), role, np.array(f.density), np.array(f.color), f.to_world)
              for role, f in integ.fields.items()}
    cam = mi.ScalarTransform4f().look_at(origin=[0.5, 0.3, -4], target=[0, 0, 0], up=[0, 1, 0])
    write_scene(str(tmp_path / "scene.xml"), bodies, {"samples": 16, "composition": "c4"},
                [sensor_xml(np.array(cam.matrix), 40.0, 8, 6)])
    spec = {"type": "scene", "integrator": {"type": "voldis", "samples": 16, "composition": "c4",
                                            "full": full, "bg": bg},
            "sensor": {"type": "perspective", "fov": 40.0, "fov_axis": "x", "near_clip": 1e-4, "to_world": cam,
                       "film": {"type": "hdrfilm", "width": 8, "height": 6, "pixel_format": "rgb",
                                "rfilter": {"type": "box"}}, "sampler": {"type": "independent", "sample_count": 1}}}
    return tmp_path / "scene.xml", spec


def test_xml_file_and_dict_render_the_same(tmp_path):
    path, spec = scene_files(tmp_path)
    from_file = np.array(mi.render(mi.load_file(str(path)), seed=7))
    from_dict = np.array(mi.render(mi.load_dict(spec), seed=7))
    np.testing.assert_array_equal(from_file, from_dict)
    from_string = mi.load_string(path.read_text().replace('value="full_', f'value="{tmp_path}/full_')
                                 .replace('value="bg_', f'value="{tmp_path}/bg_'))
    np.testing.assert_array_equal(np.array(mi.render(from_string, seed=7)), from_dict)


def test_render_script(tmp_path):
    path, _ = scene_files(tmp_path)
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "render.py"), str(path), "--out", str(out),
                          "--width", "10", "--height", "8", "--spp", "2"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    back = read_exr(out / "view000.exr")
    assert back["R"].shape == (8, 10) and "fg_depth.Z" in back and "depth.Z" in back
    assert os.path.isfile(out / "view000_composite.png")
    bad = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "render.py"), str(tmp_path / "nope.xml"),
                          "--out", str(out)], capture_output=True, text=True)
    assert bad.returncode != 0 and "nope.xml" in bad.stderr


def test_bad_vol_files_name_the_file(tmp_path):
    write_vol(tmp_path / "ok.vol", np.zeros((2, 2, 2, 1)))
    data = (tmp_path / "ok.vol").read_bytes()
    (tmp_path / "short.vol").write_bytes(data[:-8])
    (tmp_path / "junk.vol").write_bytes(b"not a volume at all, but long enough to have a header......")
    for name, message in (("short.vol", "truncated"), ("junk.vol", "not a Mitsuba .vol"),
                          ("missing.vol", "cannot read")):
        with pytest.raises(ValueError, match=f"{name}.*{message}|{message}.*{name}"):
            read_vol(tmp_path / name)
    with pytest.raises(RuntimeError, match="short.vol"):
        mi.load_dict({"type": "radiance_field", "density": str(tmp_path / "short.vol"),
                      "color": str(tmp_path / "ok.vol")})


@pytest.mark.parametrize("props, message", [
    ({"density": np.zeros((2, 2, 2, 2))}, "density must have shape"),
    ({"color": np.zeros((2, 2, 2, 4))}, "color needs 3, 6, 12 or 27 channels"),
    ({"color": np.zeros((3, 2, 2, 3))}, "color must have shape"),
    ({"density": np.full((2, 2, 2, 1), np.nan)}, "NaN or Inf"),
    ({"density": np.zeros((1, 2, 2, 1)), "color": np.zeros((1, 2, 2, 3))}, "at least 2 vertices"),
    ({"to_world": np.diag([1.0, 0.0, 1.0, 1.0])}, "non-zero volume"),
])
def test_field_property_errors(props, message):
    spec = {"type": "radiance_field", "density": np.zeros((2, 2, 2, 1)), "color": np.zeros((2, 2, 2, 3))}
    spec.update(props)
    for key in ("density", "color"):
        spec[key] = mi.TensorXf(spec[key].astype(np.float32))
    if "to_world" in spec:
        spec["to_world"] = mi.ScalarTransform4f(spec["to_world"].astype(np.float32))
    with pytest.raises(RuntimeError, match=message):
        mi.load_dict(spec)


@pytest.mark.parametrize("props, message", [
    ({"composition": "c5"}, "composition must be one of"),
    ({"mode": "alpha"}, "mode must be one of"),
    ({"samples": 0}, "samples must be >= 1"),
    ({"bg": None}, "'bg' radiance_field medium is required"),
    ({"extra": random_field(9)}, "unknown field role 'extra'"),
])
def test_integrator_property_errors(props, message):
    spec = {"type": "voldis", "full": random_field(7),
            "bg": random_field(8, to_world=box_transform([0, 0, 0], [1, 1, 1]))}
    spec.update(props)
    spec = {k: v for k, v in spec.items() if v is not None}
    with pytest.raises(RuntimeError, match=message):
        mi.load_dict(spec)


def test_forward_mode_is_refused_clearly():
    scene = ortho_scene({"type": "voldis", "samples": 4, "full": random_field(1), "bg": random_field(2)})
    params = mi.traverse(scene)
    dr.enable_grad(params["integrator.full.density"])
    with pytest.raises(Exception, match="forward-mode"):
        scene.integrator().render_forward(scene, params)


@pytest.mark.parametrize("keep", [False, True])
def test_a_finished_job_drops_its_checkpoints_unless_kept(tmp_path, keep):
    from mi_voldis.io.run_folder import CHECKPOINTS, staged
    out = str(tmp_path / "run")
    with staged(out, keep_checkpoints=keep) as stage:
        os.makedirs(os.path.join(stage, CHECKPOINTS))
        with open(os.path.join(stage, CHECKPOINTS, "last.npz"), "wb") as f:
            f.write(b"state")
        with open(os.path.join(stage, "metrics.json"), "w") as f:
            f.write("{}")
    assert os.path.isfile(os.path.join(out, "metrics.json"))
    assert os.path.isfile(os.path.join(out, CHECKPOINTS, "last.npz")) == keep
    assert not os.path.exists(out + ".partial")
