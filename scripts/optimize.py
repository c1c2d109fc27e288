"""Run a manipulation task on a fitted run.

    python scripts/optimize.py --task {removal,transform,camouflage,nonneg,semantic} RUN [options]

transform: --scale S --rotate AXIS:DEG --translate X,Y,Z [--pivot X,Y,Z] [--composition RULE]
           (or --dataset-transform: the dataset's own moved_transform, to compare with its ground truth)
semantic:  --prompt TEXT --clip-model PATH (a local Hugging Face CLIP folder; pip install .[clip])
Writes RUN/<task>/ (volumes, scene.xml, EXR layers, previews, metrics.json, loss.png).
"""
import argparse
import json
import os
import sys

TASKS = ("removal", "transform", "camouflage", "nonneg", "semantic")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", help="run directory written by scripts/train.py")
    ap.add_argument("--task", required=True, choices=TASKS)
    ap.add_argument("--dataset", help="dataset folder (default: the one the run was fitted on)")
    ap.add_argument("--steps", type=int, help="optimisation steps (optimised tasks)")
    ap.add_argument("--resume", action="store_true", help="continue RUN/<task>.partial from its checkpoint")
    ap.add_argument("--checkpoint-every", type=int, help="steps between checkpoints (default 100)")
    ap.add_argument("--composition", help="paper, c2, c3, c4 or density")
    ap.add_argument("--scale", type=float)
    ap.add_argument("--rotate", help="AXIS:DEG, e.g. y:30")
    ap.add_argument("--translate", help="X,Y,Z in world units")
    ap.add_argument("--pivot", help="X,Y,Z (default: the foreground's centre)")
    ap.add_argument("--dataset-transform", action="store_true", help="transform: use the dataset's moved_transform")
    ap.add_argument("--prompt", help="semantic: the text to steer the foreground's colours towards")
    ap.add_argument("--clip-model", help="semantic: local CLIP model folder")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant")
    ap.add_argument("--quiet", action="store_true", help="no progress bars")
    args = ap.parse_args(argv)
    os.environ["MI_VOLDIS_VARIANT"] = args.variant
    from mi_voldis.tasks import run_task
    options = {"steps": args.steps, "resume": args.resume, "checkpoint_every": args.checkpoint_every,
               "composition": args.composition, "scale": args.scale,
               "rotate": args.rotate, "translate": args.translate, "pivot": args.pivot,
               "use_dataset_transform": args.dataset_transform, "prompt": args.prompt, "clip_model": args.clip_model,
               "seed": args.seed, "progress": not args.quiet}
    try:
        out = run_task(args.run, args.task, options, args.dataset)
    except ValueError as e:
        sys.exit(f"error: {e}")
    with open(os.path.join(out, "metrics.json")) as f:
        metrics = json.load(f)
    print(json.dumps({"output": out, **{k: v for k, v in metrics.items() if k != "per_view"}}, indent=1))


if __name__ == "__main__":
    main()
