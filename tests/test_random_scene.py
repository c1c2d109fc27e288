"""Random scenes (scripts/make_dataset.py --random): one scene per seed, loadable, the object present,
every camera ray ending on a surface, and rendered into a dataset the loader reads."""
import os
import subprocess
import sys

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_voldis.data import load_dataset
from mi_voldis.synth import family, make, variants
from mi_voldis.synth.random_scene import KINDS, random_scene, write_random_scene

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_a_seed_names_one_scene_and_seeds_differ():
    a, b = random_scene(3), random_scene(3)
    assert a[0] == b[0] and a[1] == b[1] and a[2].keys() == b[2].keys()
    assert all(np.array_equal(a[2][k], b[2][k]) for k in a[2])
    assert len({random_scene(s)[0] for s in range(6)}) == 6
    kinds = {random_scene(s)[1]["cameras"]["type"] for s in range(12)}
    assert kinds == {"orbit", "forward"}


@pytest.mark.parametrize("seed", range(6))
def test_scene_loads_holds_the_object_and_every_ray_ends_on_a_surface(tmp_path, seed):
    path = write_random_scene(seed, str(tmp_path), views=12)
    root = variants.parse(path)
    variants.check_object(root, "object", path)
    mi.file_resolver().prepend(str(tmp_path))
    scene = mi.load_file(path)
    rig = make.load_rig(path)
    for cam in make.make_cameras(rig, rig["views"], 32, 24):
        sensor = mi.load_dict(cam.sensor_dict())
        y, x = np.mgrid[0:24, 0:32]
        pos = mi.Point2f(*((np.stack([x.ravel(), y.ravel()]) + 0.5) / [[32], [24]]).astype(np.float32))
        rays, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5))
        assert dr.all(scene.ray_intersect(rays).is_valid()), f"seed {seed}: a camera ray leaves the scene"


def test_make_dataset_random_writes_a_dataset_with_ground_truth(tmp_path):
    out = tmp_path / "r1"
    done = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "make_dataset.py"), "--random", "1", "--out",
                           str(out), "--views", "8", "--res", "32x24", "--spp", "4"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert (out / "scene" / "scene.xml").is_file() and (out / "scene" / "scene.json").is_file()
    ds = load_dataset(str(out))
    assert ds.masks is not None and ds.backgrounds is not None and ds.masks.any()
    assert len(ds.train) and len(ds.test)


@pytest.mark.parametrize("kind", KINDS)
def test_family_kinds_load_hold_the_object_and_every_ray_ends_on_a_surface(tmp_path, kind):
    for seed in (1000, 1001):
        path = write_random_scene(seed, str(tmp_path / f"{kind}{seed}"), kind=kind)
        root = variants.parse(path)
        variants.check_object(root, "object", path)
        mi.file_resolver().prepend(str(tmp_path / f"{kind}{seed}"))
        scene = mi.load_file(path)
        rig = make.load_rig(path)
        assert make.forward_facing(rig) == (kind in ("forward", "handheld"))
        for cam in make.make_cameras(rig, rig["views"], 32, 24):
            sensor = mi.load_dict(cam.sensor_dict())
            y, x = np.mgrid[0:24, 0:32]
            pos = mi.Point2f(*((np.stack([x.ravel(), y.ravel()]) + 0.5) / [[32], [24]]).astype(np.float32))
            rays, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5))
            assert dr.all(scene.ray_intersect(rays).is_valid()), f"{kind} {seed}: a camera ray leaves the scene"


def test_hand_held_arcs_cover_part_of_the_circle_unevenly():
    """An arc's views span less than the full circle, and their spacing is uneven (crowded to one end)."""
    for seed in range(1000, 1006):
        rig = random_scene(seed, kind="arc")[1]["cameras"]
        pos, target = np.array(rig["positions"]), np.mean(rig["targets"], axis=0)
        az = np.sort(np.degrees(np.arctan2(pos[:, 0] - target[0], pos[:, 2] - target[2])) % 360)
        gaps = np.diff(np.concatenate([az, az[:1] + 360]))
        assert gaps.max() > 50  # the part of the circle no view covers
        inner = np.sort(gaps)[:-1]
        assert inner.max() > 3 * np.median(inner)


def test_a_path_rig_refuses_another_view_count(tmp_path):
    path = write_random_scene(1002, str(tmp_path), kind="arc")
    rig = make.load_rig(path)
    with pytest.raises(ValueError, match="path of 30 cameras"):
        make.make_cameras(rig, 12, 32, 24)


def test_the_family_split_is_fixed_disjoint_and_balanced_between_rigs():
    assert len(family.TUNING) == 10 and len(family.CHECK) >= 10
    assert sorted(family.TUNING + family.CHECK) == list(range(family.SIZE))
    assert not set(family.TUNING) & set(family.CHECK)
    for half in (family.TUNING, family.CHECK):
        kinds = [family.scene(k)[1] for k in half]
        forward = sum(k in ("forward", "handheld") for k in kinds)
        assert forward == len(half) - forward  # forward-facing as often as orbits
    assert {family.half(k) for k in family.TUNING} == {"tuning"} and {family.half(k) for k in family.CHECK} == {"check"}
    assert family.index(family.name(13)) == 13 and family.index("random3") is None and family.index("family99") is None
    with pytest.raises(ValueError, match=f"0 to {family.SIZE - 1}"):
        family.scene(family.SIZE)


def test_make_dataset_family_writes_a_forward_facing_hand_held_dataset(tmp_path):
    out = tmp_path / "f3"
    done = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "make_dataset.py"), "--family", "3", "--out",
                           str(out), "--res", "32x24", "--spp", "4"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert (out / "poses_bounds.npy").is_file()
    ds = load_dataset(str(out))
    assert ds.masks is not None and ds.masks.any() and len(ds.cameras) == 20
    bad = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "make_dataset.py"), "--family",
                          str(family.SIZE), "--out", str(tmp_path / "x")], capture_output=True, text=True)
    assert bad.returncode != 0 and f"--family must be from 0 to {family.SIZE - 1}" in bad.stderr
    assert "Traceback" not in bad.stderr
