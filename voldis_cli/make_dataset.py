"""Render a dataset with ground truth from a bundled Mitsuba scene, or from a random one.

    python scripts/make_dataset.py scenes/NAME.xml --out data/NAME [--views N --res WxH --spp S --seed K]
    python scripts/make_dataset.py --random SEED --out data/random_SEED [--views N --res WxH --spp S]
    python scripts/make_dataset.py --family K --out data/familyK
    python scripts/make_dataset.py scenes/NAME.xml --out data/NAME_spinnerf --layout spinnerf [--views 100]

The rig (cameras, resolution, the "moved" edit) comes from scenes/NAME.json; the flags override it.
--random composes a scene from the seed (mi_voldis/synth/random_scene.py: layout, object parts,
materials, a mirror sometimes, an occluder sometimes, a shadow-casting light, a 360-degree or
forward-facing rig) and keeps it in the dataset's scene/ folder. --family K makes scene K of the removal
family (mi_voldis/synth/family.py: 24 harder random scenes, hand-held rigs, close walls, area lights;
the first ten tune the defaults, the rest judge them). --layout spinnerf writes SPIn-NeRF's
LLFF layout: the first 40% of the views by name without the object (images_4/test_label/ marks where
it stood), the rest with it (images_4/label/).
"""
import argparse
import os
import sys

from .boundary import add_debug, positive, run


def main(argv=None):
    from mi_voldis.synth import family
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", nargs="?", help="Mitsuba XML scene whose object shapes have ids starting with 'object'")
    ap.add_argument("--random", type=int, metavar="SEED", help="a random scene made from SEED instead of SCENE")
    ap.add_argument("--family", type=int, metavar="K",
                    help=f"scene K (0 to {family.SIZE - 1}) of the removal family instead of SCENE")
    ap.add_argument("--out", required=True, help="output dataset folder (replaced when complete)")
    ap.add_argument("--views", type=positive, help="number of views")
    ap.add_argument("--res", help="resolution WxH, e.g. 160x120")
    ap.add_argument("--spp", type=positive, help="path-tracing samples per pixel")
    ap.add_argument("--seed", type=int, default=0, help="random seed (the output is deterministic for it)")
    ap.add_argument("--holdout", type=int, default=8, help="every k-th view is a test view")
    ap.add_argument("--layout", default="transforms", choices=("transforms", "spinnerf"),
                    help="transforms.json with every ground truth, or SPIn-NeRF's removal layout")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant")
    ap.add_argument("--quiet", action="store_true", help="no progress, print nothing but errors")
    add_debug(ap)
    args = ap.parse_args(argv)
    if args.holdout < 0 or args.holdout == 1:
        ap.error(f"--holdout must be 0 (no test views) or k >= 2 (every k-th view a test view), got {args.holdout}")
    if args.views is not None and args.views < 2:
        ap.error(f"--views must be at least 2, got {args.views}")
    resolution = None
    if args.res:
        try:
            resolution = tuple(int(v) for v in args.res.lower().split("x"))
            assert len(resolution) == 2 and min(resolution) > 0
        except (ValueError, AssertionError):
            ap.error(f"--res must look like 160x120, got '{args.res}'")
    if sum(x is not None for x in (args.scene, args.random, args.family)) != 1:
        ap.error("give a SCENE file, --random SEED or --family K (one of them)")
    if args.family is not None and not 0 <= args.family < family.SIZE:
        ap.error(f"--family must be from 0 to {family.SIZE - 1}, got {args.family}")
    if args.random is not None and args.random < 0:
        ap.error(f"--random must be a seed >= 0, got {args.random}")
    if args.scene is not None and not os.path.isfile(args.scene):
        raise ValueError(f"{args.scene}: no such scene file")
    os.environ["MI_VOLDIS_VARIANT"] = args.variant
    from mi_voldis.synth.make import make_dataset
    if args.scene is not None:
        out = make_dataset(args.scene, args.out, args.views, resolution, args.spp, args.seed, args.holdout,
                           progress=not args.quiet, layout=args.layout)
        if not args.quiet:
            print(out)
        return
    import tempfile

    from mi_voldis.synth.random_scene import write_random_scene
    seed, kind = (args.random, None) if args.family is None else family.scene(args.family)
    with tempfile.TemporaryDirectory() as folder:
        scene = write_random_scene(seed, folder, args.views, kind)
        out = make_dataset(scene, args.out, args.views, resolution, args.spp, args.seed, args.holdout,
                           progress=not args.quiet, scene_folder=folder, layout=args.layout)
    if not args.quiet:
        print(out)


def entry():
    """The console command (``[project.scripts]`` in pyproject.toml)."""
    sys.exit(run(main))
