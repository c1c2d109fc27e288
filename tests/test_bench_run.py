"""What the benchmark's fit record measures of a run folder."""
import os

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

    from mi_voldis.bench.run import finished
    dataset = json.load(open(os.path.join(tiny_run, "config.json")))["dataset"]["path"]
    assert finished(tiny_run, dataset, TINY_FIT)
    assert not finished(tiny_run, dataset, TINY_FIT + ["seed=1"])  # other settings: fitted again
    assert not finished(tiny_run, os.path.dirname(dataset), TINY_FIT)  # another dataset
