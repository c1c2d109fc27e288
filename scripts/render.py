"""Render a voldis scene to layered EXRs and PNG previews.

    python scripts/render.py SCENE.xml --out DIR [--spp N] [--width W --height H] [--variant V]
    python scripts/render.py RUN/scene.xml --cameras DATASET --split test --out DIR

Writes, per sensor of the scene (or per camera of a dataset split), DIR/<name>.exr (R, G, B, A,
depth.Z, full.*, bg.*, fg.*; colours in linear light) and PNG previews DIR/<name>_<layer>.png.
"""
import argparse
import os
import sys


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", help="Mitsuba XML scene with a 'voldis' integrator")
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene's)")
    ap.add_argument("--width", type=int, help="override the films' width")
    ap.add_argument("--height", type=int, help="override the films' height")
    ap.add_argument("--cameras", help="render from this dataset's cameras instead of the scene's sensors")
    ap.add_argument("--split", default="test", choices=("train", "test", "all"), help="views of --cameras")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (default: llvm_ad_rgb)")
    args = ap.parse_args(argv)
    if (args.width is None) != (args.height is None):
        ap.error("--width and --height go together")

    os.environ["MI_VOLDIS_VARIANT"] = args.variant  # chosen before the first import of mi_voldis
    import mitsuba as mi

    from mi_voldis.export import render_scene_files

    if not os.path.isfile(args.scene):
        sys.exit(f"error: {args.scene}: no such scene file")
    scene = mi.load_file(args.scene)
    size = (args.width, args.height) if args.width else None
    cameras = None
    if args.cameras:
        from mi_voldis.data import DatasetError, load_dataset
        try:
            ds = load_dataset(args.cameras)
        except DatasetError as e:
            sys.exit(f"error: {e}")
        views = range(len(ds.cameras)) if args.split == "all" else (ds.test if args.split == "test" else ds.train)
        cameras = [(os.path.splitext(ds.names[v])[0], ds.cameras[v]) for v in views]
    for path in render_scene_files(scene, args.out, spp=args.spp, size=size, cameras=cameras):
        print(path)


if __name__ == "__main__":
    main()
