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
