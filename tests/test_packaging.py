"""The wheel: built from the checkout as `pip install .` builds it, it holds the bundled scenes (with
every texture they refer to), and the installed package finds them and runs the benchmark's children
without the checkout's scripts/."""
import json
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """The project's wheel, built offline (no build isolation: the test extra's setuptools) from a copy of
    the checkout, so that the build's own folders never land in the shared working tree."""
    try:
        from setuptools import __version__ as setuptools_version
    except ImportError:
        pytest.skip("setuptools is not installed (pip install -e '.[test]')")
    if int(setuptools_version.split(".")[0]) < 77:
        pytest.skip(f"setuptools {setuptools_version} < 77, which pyproject.toml's licence field needs "
                    "(pip install -e '.[test]')")
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(os.path.join(ROOT, name), src / name)
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info")
    for name in ("mi_voldis", "voldis_cli", "scenes"):  # the package's scenes link stays a link to scenes/
        shutil.copytree(os.path.join(ROOT, name), src / name, symlinks=True, ignore=ignore)
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                            "-w", str(tmp / "dist"), str(src)], capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stderr
    [path] = (tmp / "dist").glob("mi_voldis-*.whl")
    return path


def test_the_wheel_holds_the_bundled_scenes_and_every_file_they_refer_to(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    for scene in ("tabletop", "room"):
        assert f"mi_voldis/scenes/{scene}.xml" in names and f"mi_voldis/scenes/{scene}.json" in names
        with zipfile.ZipFile(wheel).open(f"mi_voldis/scenes/{scene}.xml") as f:
            files = [e.get("value") for e in ET.parse(f).iter("string") if e.get("name") == "filename"]
        assert files, scene
        for file in files:
            assert f"mi_voldis/scenes/{file}" in names, f"{scene}.xml refers to {file}, not in the wheel"
    # the programs the benchmark starts as python -m voldis_cli NAME
    assert "voldis_cli/__main__.py" in names and "voldis_cli/make_dataset.py" in names
    assert not any(n.startswith(("scripts/", "scenes/", "tests/")) for n in names)


def test_the_installed_package_finds_its_scene_and_runs_the_benchmarks_dataset_child(wheel, tmp_path):
    """From the unpacked wheel (first on the path, started elsewhere than the checkout): the demo's default
    scene is the package's own, and the benchmark's child for a bundled dataset (``scripts/make_dataset.py``
    in its report) renders it, with its textures, though no scripts/ folder is installed."""
    site = tmp_path / "site"
    zipfile.ZipFile(wheel).extractall(site)
    out = tmp_path / "data"
    code = (
        "import json, os, sys\n"
        "import mi_voldis\n"
        "from mi_voldis.synth import bundled_scene\n"
        "from mi_voldis.bench import run\n"
        "scene = bundled_scene('tabletop')\n"
        "run.child(['scripts/make_dataset.py', scene, '--out', sys.argv[1], '--views', '3', '--res', '16x12',\n"
        "           '--spp', '1', '--quiet'], sys.argv[2])\n"
        "print(json.dumps({'package': mi_voldis.__file__, 'scene': scene, 'root': run.ROOT}))\n")
    # the wheel first; what else PYTHONPATH holds (the dependencies where they are not installed, as on a
    # machine given them as a folder) after it
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site)] + [p for p in os.environ.get("PYTHONPATH", "")
                                                                      .split(os.pathsep) if p])}
    done = subprocess.run([sys.executable, "-c", code, str(out), str(tmp_path / "child.log")], capture_output=True,
                          text=True, cwd=tmp_path, env=env, timeout=300)
    assert done.returncode == 0, done.stderr + (tmp_path / "child.log").read_text()
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert found["package"] == str(site / "mi_voldis" / "__init__.py")
    assert found["scene"] == str(site / "mi_voldis" / "scenes" / "tabletop.xml") and found["root"] == str(site)
    assert not (site / "scripts").exists()
    with open(out / "transforms.json") as f:
        frames = json.load(f)["frames"]
    assert len(frames) == 3 and all((out / fr["file_path"]).is_file() for fr in frames)


COMMANDS = ("voldis-train", "voldis-edit", "voldis-render", "voldis-make-dataset", "voldis-make-masks",
            "voldis-evaluate", "voldis-export-vol", "voldis-bench", "voldis-demo")


def test_the_wheel_installed_by_pip_into_a_fresh_venv_runs_its_commands(wheel, tmp_path):
    """``pip install`` of the wheel into a new venv, then its console commands as a user runs them (the
    wrappers pip writes into the venv's bin/, from a folder outside the checkout, no PYTHONPATH): the nine
    commands' ``--help``, and ``voldis-make-dataset`` on the bundled scene the installed package names.
    The venv is made without pip and the wheel installed with --no-deps (offline); it sees the test
    interpreter's site-packages, for the dependencies only, through a .pth line that comes after its own
    site-packages (a folder a .pth names is only appended to sys.path: its own .pth files, such as a
    checkout's editable install, are not run), so the mi_voldis imported is the one pip installed."""
    import site
    import sysconfig

    venv = tmp_path / "venv"
    made = subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], capture_output=True,
                          text=True, timeout=120)
    assert made.returncode == 0, made.stderr
    python = venv / "bin" / "python"
    purelib = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                             capture_output=True, text=True, timeout=60).stdout.strip()
    given = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep)  # dependencies given as folders
             if p and os.path.abspath(p) != os.path.abspath(ROOT)]
    deps = [p for p in site.getsitepackages() + [sysconfig.get_path("purelib"), sysconfig.get_path("platlib")] + given
            if os.path.isdir(p)]
    with open(os.path.join(purelib, "_test_dependencies.pth"), "w") as f:
        f.write("\n".join(dict.fromkeys(deps)) + "\n")
    installed = subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps",
                                "--no-index", "-q", str(wheel)], capture_output=True, text=True, timeout=300)
    assert installed.returncode == 0, installed.stderr

    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    cwd = tmp_path / "elsewhere"
    cwd.mkdir()

    def command(*args):
        done = subprocess.run([str(a) for a in args], capture_output=True, text=True, cwd=cwd, env=env,
                              timeout=300)
        assert done.returncode == 0, f"{' '.join(map(str, args))}:\n{done.stdout}\n{done.stderr}"
        return done.stdout

    where = json.loads(command(python, "-c", "import json, mi_voldis; from mi_voldis.synth import bundled_scene; "
                                             "print(json.dumps([mi_voldis.__file__, bundled_scene('tabletop')]))"))
    package, scene = (os.path.realpath(p) for p in where)
    assert package == os.path.realpath(os.path.join(purelib, "mi_voldis", "__init__.py"))
    assert not package.startswith(os.path.realpath(ROOT) + os.sep)
    assert scene == os.path.realpath(os.path.join(purelib, "mi_voldis", "scenes", "tabletop.xml"))
    for name in COMMANDS:
        script = venv / "bin" / name
        assert script.is_file(), f"pip wrote no {name} into the venv's bin/"
        assert "usage:" in command(script, "--help"), name
    out = tmp_path / "data"
    command(venv / "bin" / "voldis-make-dataset", scene, "--out", out, "--views", "2", "--res", "16x12",
            "--spp", "1", "--quiet")
    with open(out / "transforms.json") as f:
        frames = json.load(f)["frames"]
    assert len(frames) == 2 and all((out / fr["file_path"]).is_file() for fr in frames)
