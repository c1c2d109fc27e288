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
from mi_voldis.synth import make, variants
from mi_voldis.synth.random_scene import random_scene, write_random_scene

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
