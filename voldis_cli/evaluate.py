"""Score a run's removal against a dataset's ground-truth backgrounds (SPIn-NeRF's protocol).

    python scripts/evaluate.py RUN DATASET [--dilate F] [--out FILE.json]
    python scripts/evaluate.py RUN DATASET --lpips-weights DIR   (pip install .[lpips])

DATASET: a SPIn-NeRF folder (images_4/label for training views, images_4/test_label for the test
views photographed without the object) or a transforms.json dataset with background_path ground truth
(the bundled and random scenes). Prints (and with --out writes) PSNR / SSIM over the whole image,
inside the dilated mask and inside the mask's bounding box, per view and their means; LPIPS with a
local weights folder (see mi_voldis/lpips.py for the files it needs). --out is refused where it
names one of the run's or the dataset's files, or an existing file that is not an earlier score file.
"""
import json
import os
import sys

from .boundary import add_debug, check_run, parser_of, run, variant_first


def main(argv=None):
    variant_first(argv)
    ap = parser_of(__doc__)
    ap.add_argument("run", help="run folder written by scripts/train.py")
    ap.add_argument("dataset", nargs="?", help="dataset with ground truth (default: the run's own)")
    ap.add_argument("--dilate", type=float, default=0.01, help="mask dilation, fraction of the image diagonal")
    ap.add_argument("--lpips-weights", help="folder with LPIPS weights (see mi_voldis/lpips.py)")
    ap.add_argument("--out", help="also write the scores to this JSON file")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant")
    ap.add_argument("--quiet", action="store_true", help="print only the means")
    add_debug(ap)
    args = ap.parse_args(argv)
    if not 0 <= args.dilate < 0.5:
        ap.error(f"--dilate must be in [0, 0.5), got {args.dilate}")
    check_run(args.run)
    from mi_voldis.evaluate import evaluate_removal
    from mi_voldis.tasks.base import FittedRun
    fitted = FittedRun(args.run, args.dataset)
    perceptual = None
    if args.lpips_weights:
        from mi_voldis.lpips import load_lpips
        perceptual = load_lpips(args.lpips_weights)
    ds = fitted.dataset
    if args.out:
        check_scores_file(args.out, args.run, ds.root)
    scores = evaluate_removal(fitted.integrator(), ds, args.dilate, perceptual)
    if not scores["views"]:
        raise ValueError(f"{ds.root}: no test view has a ground-truth background and an object mask "
                         "(SPIn-NeRF's images_K/test_label/ or transforms.json background_path)")
    scores = {"run": args.run, "dataset": ds.root, **scores}
    if args.out:
        from mi_voldis.io.run_folder import write_json
        write_json(args.out, scores)
    print(json.dumps({k: v for k, v in scores.items() if k != "per_view" or not args.quiet}, indent=1))


def check_scores_file(path, run, dataset):
    """``--out`` may be a new file or an earlier score file, never an input of the run or the dataset."""
    from mi_voldis.io.run_folder import check_inputs, dataset_inputs, run_files
    check_inputs(path, run_files(run) + dataset_inputs(dataset))
    if os.path.isdir(path):
        raise ValueError(f"{path}: is a folder; --out names the JSON file to write")
    if os.path.lexists(path):
        try:
            with open(path) as f:
                earlier = json.load(f)
        except (OSError, ValueError):
            earlier = None
        if not (isinstance(earlier, dict) and {"run", "dataset", "views"} <= set(earlier)):
            raise ValueError(f"{path}: exists and is not a score file of scripts/evaluate.py, so it is not "
                             "overwritten; choose another --out")


def entry():
    """The console command (``[project.scripts]`` in pyproject.toml)."""
    sys.exit(run(main))
