"""Render a voldis scene to layered EXRs and PNG previews.

    python scripts/render.py SCENE.xml --out DIR [--spp N] [--width W --height H] [--variant V]

Writes, per sensor of the scene, DIR/viewNNN.exr (R, G, B, A, depth.Z, full.*, bg.*, fg.*) and
sRGB PNG previews DIR/viewNNN_<layer>.png.
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
    for path in render_scene_files(scene, args.out, spp=args.spp, size=size):
        print(path)


if __name__ == "__main__":
    main()
