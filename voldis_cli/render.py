"""Render a voldis scene to layered EXRs and PNG previews.

    python scripts/render.py SCENE.xml --out DIR [--spp N] [--width W --height H] [--variant V]
    python scripts/render.py RUN/scene.xml --cameras DATASET --split test --out DIR

With --cameras, the views (split, downscale factor) are those the run was fitted with, read from the
config.json beside SCENE.xml when there is one.

Writes, per sensor of the scene (or per camera of a dataset split), DIR/<name>.exr (R, G, B, A,
depth.Z, full.*, bg.*, fg.*; colours in linear light) and PNG previews DIR/<name>_<layer>.png.
"""
import argparse
import os
import sys

from .boundary import add_debug, positive, run


def run_record(folder):
    """The dataset record of the run folder holding the scene (its config.json), or None."""
    import json
    try:
        with open(os.path.join(folder, "config.json")) as f:
            record = json.load(f).get("dataset")
    except (OSError, ValueError, AttributeError):
        return None
    return record if isinstance(record, dict) and record.get("path") else None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", help="Mitsuba XML scene with a 'voldis' integrator")
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--spp", type=positive, default=None, help="samples per pixel (default: the scene's)")
    ap.add_argument("--width", type=positive, help="override the films' width")
    ap.add_argument("--height", type=positive, help="override the films' height")
    ap.add_argument("--cameras", help="render from this dataset's cameras instead of the scene's sensors")
    ap.add_argument("--split", default="test", choices=("train", "test", "all"), help="views of --cameras")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (default: llvm_ad_rgb)")
    ap.add_argument("--quiet", action="store_true", help="print nothing but errors")
    add_debug(ap)
    args = ap.parse_args(argv)
    if (args.width is None) != (args.height is None):
        ap.error("--width and --height go together")
    if os.path.exists(args.out) and not os.path.isdir(args.out):
        raise ValueError(f"{args.out}: exists and is not a folder")

    os.environ["MI_VOLDIS_VARIANT"] = args.variant  # chosen before the first import of mi_voldis
    from mi_voldis.export import render_scene_files
    from mi_voldis.scene import load_scene

    scene = load_scene(args.scene)
    size = (args.width, args.height) if args.width else None
    cameras = None
    if args.cameras:
        from mi_voldis.data import load_dataset
        from mi_voldis.tasks.base import load_recorded
        record = run_record(os.path.dirname(os.path.abspath(args.scene)))
        ds = load_recorded(record, args.cameras) if record else load_dataset(args.cameras)
        views = range(len(ds.cameras)) if args.split == "all" else (ds.test if args.split == "test" else ds.train)
        if not len(views):
            raise ValueError(f"{args.cameras}: no {args.split} views to render")
        cameras = [(os.path.splitext(ds.names[v])[0], ds.cameras[v]) for v in views]
    elif not scene.sensors():
        raise ValueError(f"{args.scene}: the scene has no sensor; give --cameras DATASET")
    for path in render_scene_files(scene, args.out, spp=args.spp, size=size, cameras=cameras):
        if not args.quiet:
            print(path)


def entry():
    """The console command (``[project.scripts]`` in pyproject.toml)."""
    sys.exit(run(main))
