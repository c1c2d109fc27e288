"""Fit the full-scene and background radiance fields of a dataset.

    python scripts/train.py DATASET --out RUN [--variant V] [--config FILE] [--set name=value ...]
                            [--resume | --restart]

Writes RUN/ (fields as <role>_grid.npz, scene.xml, config.json, metrics.json, previews/, training.png;
checkpoints/ while it runs). RUN may not be, hold or lie inside the dataset's files. A killed fit
leaves RUN.partial: --resume continues it (refused with another dataset or other settings, but
checkpoint_every, checkpoint_minutes and eval_every), --restart discards it. The settings are listed below (defined in
mi_voldis/fit/config.py).
"""
import json
import sys

from .boundary import add_debug, add_threads, parser_of, run, set_threads, variant_first


def main(argv=None):
    variant_first(argv)
    from mi_voldis.fit.config import FitConfig
    ap = parser_of(__doc__, FitConfig.help_text())
    ap.add_argument("dataset", help="dataset folder (transforms.json or LLFF poses_bounds.npy)")
    ap.add_argument("--out", required=True, help="run directory")
    ap.add_argument("--config", help="JSON file of settings (a finished run's RUN/config.json works too)")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="override one setting")
    ap.add_argument("--resume", action="store_true", help="continue RUN.partial from its last checkpoint")
    ap.add_argument("--restart", action="store_true", help="discard a resumable RUN.partial and fit afresh")
    ap.add_argument("--format", default="auto", choices=("auto", "llff", "transforms", "colmap"),
                    help="dataset format")
    ap.add_argument("--holdout", type=int, default=8, help="every k-th view is held out (without a split); 0: none")
    ap.add_argument("--factor", "--downscale", type=int, default=None, metavar="K",
                    help="read the images downscaled by K (images_K/; LLFF default: the smallest there is)")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant")
    add_threads(ap)
    ap.add_argument("--quiet", action="store_true", help="no progress bars")
    ap.add_argument("--keep-checkpoints", action="store_true", help="keep RUN/checkpoints/last.npz (the final state)")
    add_debug(ap)
    args = ap.parse_args(argv)
    if args.holdout < 0:
        ap.error(f"--holdout must be 0 (no test views) or a positive k, got {args.holdout}")
    if args.factor is not None and args.factor < 1:
        ap.error(f"--factor must be a whole number >= 1, got {args.factor}")
    set_threads(args)
    from mi_voldis.fit.run import run_fit
    cfg = FitConfig.from_sources(args.config, args.set)
    metrics = run_fit(args.dataset, args.out, cfg, args.resume, not args.quiet, args.format, args.holdout,
                      args.keep_checkpoints, args.factor, args.restart)
    print(json.dumps({"run": args.out, **metrics["held_out"], "seconds": metrics["seconds"]}, indent=1))


def entry():
    """The console command (``[project.scripts]`` in pyproject.toml)."""
    sys.exit(run(main))
