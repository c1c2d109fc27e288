"""Run a manipulation task on a fitted run.

    python scripts/optimize.py --task {removal,transform,camouflage,nonneg,semantic} RUN [--set name=value ...]

transform: --scale S --rotate AXIS:DEG --translate X,Y,Z [--pivot X,Y,Z] [--composition RULE]
           (or --dataset-transform: the dataset's own moved_transform, to compare with its ground truth)
semantic:  --prompt TEXT --clip-model PATH (a local Hugging Face CLIP folder; pip install .[clip])
Every task setting (listed below, defined in mi_voldis/tasks/settings.py) can be given with --set or
--config FILE. Writes RUN/<task>/ (volumes, scene.xml, config.json, EXR layers, previews, metrics.json,
loss.png).
"""
import json
import os
import sys

from .boundary import add_debug, add_threads, check_run, parser_of, run, set_threads, variant_first

# shorthand flags: flag -> (setting, how to read its text)
FLAGS = {"steps": ("steps", int), "checkpoint_every": ("checkpoint_every", int), "seed": ("seed", int),
         "composition": ("composition", str), "scale": ("scale", float), "rotate": ("rotate", str),
         "translate": ("translate", "vector"), "pivot": ("pivot", "vector"), "prompt": ("prompt", str),
         "clip_model": ("clip_model", str)}


def vector(text, flag):
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3:
        raise ValueError(f"--{flag.replace('_', '-')} expects X,Y,Z, got '{text}'")
    return values


def main(argv=None):
    variant_first(argv)
    from mi_voldis.tasks.settings import SETTINGS
    epilog = "\n\n".join(cls.help_text(f"{task} settings") for task, cls in SETTINGS.items())
    ap = parser_of(__doc__, epilog)
    ap.add_argument("run", help="run directory written by scripts/train.py")
    ap.add_argument("--task", required=True, choices=tuple(SETTINGS))
    ap.add_argument("--dataset", help="dataset folder (default: the one the run was fitted on)")
    ap.add_argument("--config", help="JSON file of task settings (a finished RUN/<task>/config.json works too)")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="override one setting")
    ap.add_argument("--out", help="output folder (default RUN/<task>), apart from RUN's files and the dataset; its "
                                  "scene refers to RUN's fields in place")
    ap.add_argument("--resume", action="store_true",
                    help="continue OUT.partial from its checkpoint (same task, settings and run; checkpoint_every "
                         "may change)")
    ap.add_argument("--restart", action="store_true", help="discard a resumable OUT.partial and start afresh")
    ap.add_argument("--keep-checkpoints", action="store_true", help="keep OUT/checkpoints/last.npz")
    ap.add_argument("--steps", help="optimisation steps (optimised tasks)")
    ap.add_argument("--checkpoint-every", help="steps between checkpoints")
    ap.add_argument("--seed", help="random seed")
    ap.add_argument("--composition", help="paper, c2, c3, c4 or density")
    ap.add_argument("--scale", help="transform: scale about the pivot")
    ap.add_argument("--rotate", help="transform: AXIS:DEG, e.g. y:30")
    ap.add_argument("--translate", help="transform: X,Y,Z in world units")
    ap.add_argument("--pivot", help="transform: X,Y,Z (default: the foreground's centre)")
    ap.add_argument("--dataset-transform", action="store_true", help="transform: use the dataset's moved_transform")
    ap.add_argument("--prompt", help="semantic: the text to steer the foreground's colours towards")
    ap.add_argument("--clip-model", help="semantic: local CLIP model folder")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant")
    ap.add_argument("--quiet", action="store_true", help="no progress bars")
    add_threads(ap)
    add_debug(ap)
    args = ap.parse_args(argv)
    check_run(args.run)
    set_threads(args)
    values = {}
    for flag, (name, kind) in FLAGS.items():
        text = getattr(args, flag)
        if text is None:
            continue
        if kind == "vector":
            values[name] = vector(text, flag)
            continue
        try:
            values[name] = kind(text)
        except ValueError:
            raise ValueError(f"--{flag.replace('_', '-')} expects a {kind.__name__}, got '{text}'") from None
    if args.resume:
        values["resume"] = True
    if args.dataset_transform:
        values["use_dataset_transform"] = True
    cls = SETTINGS[args.task]
    unknown = sorted(set(values) - set(cls.names()))
    if unknown:
        ap.error(f"--task {args.task} takes no {', '.join('--' + u.replace('_', '-') for u in unknown)}")
    for flag, (name, _) in FLAGS.items():  # each flag's own value checked alone, so its error names the flag
        if name in values:
            try:
                cls().replace(**{name: values[name]})
            except ValueError as e:
                raise ValueError(f"--{flag.replace('_', '-')}: {e}") from None
    settings = cls.from_sources(args.config, args.set, **values)
    from mi_voldis.tasks import run_task
    out = run_task(args.run, args.task, settings, args.dataset, progress=not args.quiet, out=args.out,
                   keep_checkpoints=args.keep_checkpoints, restart=args.restart)
    with open(os.path.join(out, "metrics.json")) as f:
        metrics = json.load(f)
    print(json.dumps({"output": out, **{k: v for k, v in metrics.items() if k != "per_view"}}, indent=1))


def entry():
    """The console command (``[project.scripts]`` in pyproject.toml)."""
    sys.exit(run(main))
