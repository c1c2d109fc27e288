"""Object masks for every view of a dataset from the masks of a few views, or from a box around the object.

    python scripts/make_masks.py DATASET --out DATASET/masks --from-views VIEW=MASK.png [VIEW=MASK.png ...]
    python scripts/make_masks.py DATASET --out DATASET/masks --box x0,y0,z0,x1,y1,z1
    python scripts/make_masks.py DATASET --out DATASET/effects --effects --from-views VIEW=SHADOW.png [...]

Fits the full field first (into --run, default OUT.run; an existing run there is reused), then lifts
the given masks or box into 3D through the field's surface (mi_voldis/masks3d.py) and writes, per view,
<image stem>.png (white = object) of the object's visible part: what stands in front of it stays
unmasked. VIEW: an image name, its stem or its index. The box is in world units (the dataset's poses),
whatever scene space the fit uses. scripts/train.py then reads DATASET/masks/. With --effects the given
masks mark the object's shadow (or reflection) on the surfaces: each view's pixels whose surface point some
given view sees inside its mask, for DATASET/effects/. OUT may replace a folder of masks that make_masks
wrote, never the dataset, its images or other files, the run or the given masks.
"""
import json
import os
import sys

from .boundary import add_debug, parser_of, run, variant_first


def parse_box(text):
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        v = []
    if len(v) != 6 or not all(a < b for a, b in zip(v[:3], v[3:])):
        raise ValueError(f"--box expects x0,y0,z0,x1,y1,z1 with x0 < x1, y0 < y1, z0 < z1, got '{text}'")
    return v[:3], v[3:]


def main(argv=None):
    variant_first(argv)
    ap = parser_of(__doc__)
    ap.add_argument("dataset", help="dataset folder (transforms.json, LLFF or COLMAP)")
    ap.add_argument("--out", required=True, help="folder of the masks to write (replaced when complete)")
    how = ap.add_mutually_exclusive_group(required=True)
    how.add_argument("--from-views", nargs="+", metavar="VIEW=MASK", help="masks of a few views")
    how.add_argument("--box", help="world-space box x0,y0,z0,x1,y1,z1 around the object")
    ap.add_argument("--effects", action="store_true",
                    help="--from-views masks are effect masks (the object's shadow): a patch of the surfaces")
    ap.add_argument("--run", help="run folder of the full field (fitted there when missing; default OUT.run)")
    ap.add_argument("--resume", action="store_true", help="continue the fit of --run from its RUN.partial")
    ap.add_argument("--restart", action="store_true", help="discard a resumable RUN.partial of --run and fit afresh")
    ap.add_argument("--format", default="auto", choices=("auto", "llff", "transforms", "colmap"))
    ap.add_argument("--factor", "--downscale", type=int, metavar="K", help="read images_K/")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="a fit setting")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant")
    ap.add_argument("--quiet", action="store_true", help="no progress bars")
    add_debug(ap)
    args = ap.parse_args(argv)
    given = None
    if args.from_views:
        given = {}
        for item in args.from_views:
            view, sep, path = item.partition("=")
            if not sep or not view or not path:
                ap.error(f"--from-views expects VIEW=MASK.png, got '{item}'")
            if not os.path.isfile(path):
                raise ValueError(f"{path}: no such mask file")
            if view in given:
                raise ValueError(f"--from-views: view '{view}' is given twice ({given[view]} and {path})")
            given[view] = path
    if args.effects and not args.from_views:
        ap.error("--effects goes with --from-views")
    box = parse_box(args.box) if args.box else None
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.masks3d import make_masks
    summary = make_masks(args.dataset, args.run or args.out.rstrip("/") + ".run", args.out, given, box, args.format,
                         args.factor, FitConfig.from_sources(None, args.set), progress=not args.quiet,
                         effects=args.effects, resume=args.resume, restart=args.restart)
    print(json.dumps(summary, indent=1))


def entry():
    """The console command (``[project.scripts]`` in pyproject.toml)."""
    sys.exit(run(main))
