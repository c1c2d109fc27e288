"""The README's main command: the whole pipeline on the bundled default scene.

    python scripts/demo.py [--scene SCENE.xml] [--out out/demo] [--spp 128] [--variant V]

Renders the dataset (Mitsuba path tracer, with ground truth), fits the full and background fields,
disentangles the object, runs removal / transform / camouflage / non-negative edits, writes layered
EXRs, previews and a contact sheet, and prints where everything is.
"""
import argparse
import json
import os
import sys

from .boundary import run


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", help="a Mitsuba scene with its rig beside it (default: the bundled tabletop scene, "
                                    "scenes/tabletop.xml, also in an installed package)")
    ap.add_argument("--out", default="out/demo")
    ap.add_argument("--spp", type=int, default=128, help="path-tracing samples per pixel of the dataset")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--composition", choices=("paper", "c2", "c3", "c4", "density"),
                    help="composition rule that moves the object (default: the best against the ground truth)")
    ap.add_argument("--quiet", action="store_true", help="no progress lines")
    args = ap.parse_args(argv)
    os.environ["MI_VOLDIS_VARIANT"] = args.variant
    from mi_voldis.demo import run_demo
    from mi_voldis.synth import bundled_scene
    scene = os.path.normpath(args.scene) if args.scene else bundled_scene("tabletop")
    try:
        summary = run_demo(args.out, scene, args.spp, not args.quiet, args.composition)
    except ValueError as e:
        sys.exit(f"error: {e}")
    fit = summary["fit"]
    print(json.dumps({"seconds": {k: round(v, 1) for k, v in summary["seconds"].items()},
                      "held_out": {k: None if v is None else round(v, 3) for k, v in fit.items()}}, indent=1))
    print(f"dataset:        {summary['dataset']}")
    print(f"fitted run:     {summary['run']}  (scene.xml, *_grid.npz, metrics.json, previews/, training.png)")
    for task in summary["tasks"]:
        print(f"{task + ':':15} {os.path.join(summary['run'], task)}  (scene.xml, viewNNN.exr, previews, metrics.json)")
    print(f"contact sheet:  {summary['contact_sheet']}")
    print(f"turntable:      {summary['turntable']}  (the moved object, left, beside the original)")
    print(summary["composition"])


def entry():
    """The console command (``[project.scripts]`` in pyproject.toml)."""
    sys.exit(run(main))
