"""Output folders never take what a job did not write: a user's folder that looks like a run, a file the
user added to a job's folder, another job's output made inside it (mi_voldis/io/run_folder.py), the
folders programs write into in place (``claim``), and ``make clean``'s venv."""
import os
import shutil
import subprocess

import pytest

from mi_voldis.io.run_folder import MARKER, check_output, claim, foreign, made_by, read_marker, staged

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def files(path):
    """{relative path: bytes} of every file under ``path``."""
    out = {}
    for d, _, names in os.walk(path):
        for n in names:
            with open(os.path.join(d, n), "rb") as f:
                out[os.path.relpath(os.path.join(d, n), path)] = f.read()
    return out


def job(out, program="train", names=("scene.xml", "previews/view000.png")):
    """A finished job of ``program`` in ``out`` that wrote ``names``."""
    with staged(out, made_by=program) as stage:
        for name in names:
            os.makedirs(os.path.dirname(os.path.join(stage, name)), exist_ok=True)
            with open(os.path.join(stage, name), "w") as f:
                f.write(name)


def test_a_folder_that_only_looks_like_a_run_is_not_replaced(tmp_path):
    """A user's Mitsuba scene folder with a scene.xml and a config.json, or another tool's run with
    checkpoints/last.npz, holds no marker: refused as an output, byte for byte as it was."""
    scene = tmp_path / "kitchen"
    (scene / "meshes").mkdir(parents=True)
    for name in ("scene.xml", "config.json", "meshes/table.ply"):
        (scene / name).write_text(name)
    other = tmp_path / "other_tool"
    (other / "checkpoints").mkdir(parents=True)
    (other / "checkpoints" / "last.npz").write_bytes(b"weights")
    for folder in (scene, other):
        before = files(folder)
        assert made_by(str(folder)) == set()
        with pytest.raises(ValueError, match=f"{folder}: exists and was not written by mi-voldis"):
            check_output(str(folder), program="train")
        with pytest.raises(ValueError, match="not written by mi-voldis"):
            with staged(str(folder), made_by="train"):
                pass
        assert files(folder) == before and not os.path.exists(f"{folder}.partial")


def test_a_job_records_what_it_left_and_is_replaced_only_while_it_holds_nothing_else(tmp_path):
    out = str(tmp_path / "run")
    job(out)
    assert read_marker(out)["files"] == ["previews", "previews/view000.png", "scene.xml"]
    assert foreign(out) == []
    job(out, names=("scene.xml",))  # its own folder: replaced whole
    assert sorted(files(out)) == [MARKER, "scene.xml"]
    # a file the user added, and another job's output made inside it (a task's RUN/removal), are named
    with open(os.path.join(out, "notes.md"), "w") as f:
        f.write("mine")
    job(os.path.join(out, "removal"), program="optimize")
    assert foreign(out) == ["notes.md", "removal"]  # outermost only: not removal's own files
    before = files(out)
    with pytest.raises(ValueError, match=f"{out}: holds notes.md, removal, which the train job that wrote it did "
                                         "not write, so it is not replaced; move them away"):
        job(out)
    assert files(out) == before and not os.path.exists(out + ".partial") and not os.path.exists(out + ".lock")
    for name in ("a.txt", "b.txt"):  # past three, the rest is counted, not listed
        with open(os.path.join(out, name), "w") as f:
            f.write(name)
    with pytest.raises(ValueError, match=f"{out}: holds a.txt, b.txt, notes.md and more, which"):
        job(out)
    for name in ("a.txt", "b.txt"):
        os.remove(os.path.join(out, name))
    # the task itself is replaced as its own job; moved away, the rest lets the run be replaced again
    job(os.path.join(out, "removal"), program="optimize", names=("view000.exr",))
    assert read_marker(os.path.join(out, "removal"))["files"] == ["view000.exr"]
    shutil.move(os.path.join(out, "notes.md"), tmp_path / "notes.md")
    shutil.move(os.path.join(out, "removal"), tmp_path / "removal")
    job(out)
    assert (tmp_path / "notes.md").read_text() == "mine" and (tmp_path / "removal" / "view000.exr").is_file()


def test_a_leftover_old_folder_holding_a_user_file_is_not_removed(tmp_path):
    """OUT.old (left by a swap a crash interrupted) is removed only when all of it is its job's."""
    out = str(tmp_path / "run")
    job(out + ".old")
    with open(os.path.join(out + ".old", "keep.txt"), "w") as f:
        f.write("mine")
    with pytest.raises(ValueError, match=r"run\.old: holds keep\.txt, which the train job that wrote it did not "
                                         "write, so it is not removed"):
        job(out)
    assert (tmp_path / "run.old" / "keep.txt").read_text() == "mine"


def test_claim_takes_only_new_empty_or_its_own_folders(tmp_path):
    own, empty, user = tmp_path / "own", tmp_path / "empty", tmp_path / "user"
    claim(str(own), "demo")
    assert made_by(str(own)) == {"demo"}
    (own / "sheet.png").write_bytes(b"png")
    claim(str(own), "demo")  # again: its own
    empty.mkdir()
    claim(str(empty), "demo")
    assert made_by(str(empty)) == {"demo"}
    user.mkdir()
    (user / "photo.jpg").write_bytes(b"jpg")
    for folder, program in ((user, "demo"), (own, "bench_masks")):
        before = files(folder)
        with pytest.raises(ValueError, match=f"{folder}: exists and was not written by {program}"):
            claim(str(folder), program)
        assert files(folder) == before
    (tmp_path / "file").write_text("x")
    with pytest.raises(ValueError, match="file: exists and is not a folder"):
        claim(str(tmp_path / "file"), "demo")


def test_the_demo_refuses_a_folder_it_did_not_make_before_any_work(tmp_path):
    from mi_voldis.demo import run_demo
    desk = tmp_path / "Desktop"
    desk.mkdir()
    (desk / "tabletop_contact_sheet.png").write_bytes(b"the user's")
    with pytest.raises(ValueError, match=f"{desk}: exists and was not written by demo"):
        run_demo(str(desk), os.path.join(ROOT, "scenes", "tabletop.xml"))
    assert files(desk) == {"tabletop_contact_sheet.png": b"the user's"}


@pytest.mark.skipif(shutil.which("make") is None, reason="no make")
def test_make_clean_removes_only_the_venv_make_made(tmp_path):
    mine, made = tmp_path / "myenv", tmp_path / "madeenv"
    for venv in (mine, made):
        (venv / "bin").mkdir(parents=True)
        (venv / "bin" / "python").write_text("")
    (made / ".made-by-make").write_text("")
    env = {**os.environ, "DRJIT_LIBLLVM_PATH": os.environ.get("DRJIT_LIBLLVM_PATH", "set")}
    said = {}
    for venv in (mine, made):
        done = subprocess.run(["make", "-s", "-C", ROOT, "clean", f"VENV={venv}"], capture_output=True, text=True,
                              env=env, timeout=120)
        assert done.returncode == 0, done.stderr
        said[venv] = done.stdout
    assert (mine / "bin" / "python").is_file() and f"{mine}: not made by make" in said[mine]
    assert not made.exists() and f"removed {made}" in said[made]


def test_writers_never_use_a_fixed_temporary_name(tmp_path):
    """A file written beside the user's (a score file, the demo's sheet) goes through a hidden temporary of
    a new name: the user's ``scores.json.tmp`` or ``sheet.tmp.png`` is not touched, and none is left."""
    import numpy as np

    from mi_voldis.io.images import write_png
    from mi_voldis.io.run_folder import temp_beside, write_json
    for name in ("scores.json.tmp", "sheet.tmp.png", "sheet.png.tmp.png"):
        (tmp_path / name).write_text("mine")
    write_json(str(tmp_path / "scores.json"), {"psnr": float("nan")})
    write_png(str(tmp_path / "sheet.png"), np.zeros((4, 4, 3), np.uint8))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scores.json", "scores.json.tmp", "sheet.png",
                                                           "sheet.png.tmp.png", "sheet.tmp.png"]
    assert all((tmp_path / n).read_text() == "mine" for n in ("scores.json.tmp", "sheet.tmp.png", "sheet.png.tmp.png"))
    assert (tmp_path / "scores.json").read_text().strip().endswith("null\n}".strip())
    a, b = temp_beside(str(tmp_path / "x.exr"), ".exr"), temp_beside(str(tmp_path / "x.exr"), ".exr")
    assert a != b and os.path.basename(a).startswith(".x.exr.") and a.endswith(".tmp.exr")
