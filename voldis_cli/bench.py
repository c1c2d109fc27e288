"""Speed against error, side by side, in one command.

    python scripts/bench.py [--quick] [--work out/bench] [--report reports]
    python scripts/bench.py --removal [--work out/bench] [--report reports] [--scenes ...]
    python scripts/bench.py --masks [--work out/bench] [--report reports] [--scenes ...]
    python scripts/bench.py --effects [--work out/bench] [--report reports] [--scenes ...]
    python scripts/bench.py --family [--work out/bench] [--report reports] [--scenes family00,...]
    python scripts/bench.py --spinnerf [--work out/bench] [--report reports] [--scenes family10,...]
                            [--lpips-weights DIR]
    python scripts/bench.py --step-profile [--rays random|tiles] [--batch N,...]   (a training step by kernel,
                            record on and off; with several batches the record at each)

Writes reports/bench.md (tables with date, machine, versions and commands), reports/bench.json and
PNG plots, into a --report folder the bench made (its .mi-voldis names it) or a new or empty one, checked
before anything runs. --quick is a smoke run of a few minutes (its report goes to out/bench/quick); the
full run fits every bundled scene, capture and random seed with the default budgets (hours on 2 cores);
--scenes picks some. --removal writes
reports/removal.md instead: every background strategy on the bundled and random ground-truth scenes;
--masks writes reports/masks.md: masks from two views (scripts/make_masks.py) and removal with them;
--effects writes reports/effects.md: removal with the object's shadow given as effect masks;
--family fits the removal family (24 random scenes, mi_voldis/synth/family.py: ten tune, the rest check) and
rewrites reports/removal.md to lead with the check half's worst scene (reports/family.json);
--spinnerf writes reports/spinnerf.md: family scenes (default the check half) rendered in SPIn-NeRF's layout
(make_dataset.py --layout spinnerf), fitted with the default command and scored with SPIn-NeRF's protocol
(whole / in-mask / bounding-box PSNR, SSIM, and LPIPS with --lpips-weights), beside Telea and Navier-Stokes
on the full field's test renders and the peers' published numbers (mi_voldis/bench/spinnerf.py).
"""
import argparse
import os
import sys

from .boundary import run


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small configurations only (a few minutes)")
    ap.add_argument("--work", default="out/bench", help="datasets, runs and logs")
    ap.add_argument("--report", help="where bench.md and the plots go (default: reports, and out/bench/quick for "
                                     "--quick, so a smoke run never replaces the full report); a folder the "
                                     "bench made, or a new or empty one")
    ap.add_argument("--step-profile", action="store_true",
                    help="only profile one training step (128^3, 128 samples/ray, 16k rays) by kernel")
    ap.add_argument("--rays", default="random", choices=("random", "tiles"),
                    help="--step-profile: random rays or fitting's tiled batches")
    ap.add_argument("--batch", default="16384", metavar="N[,N...]",
                    help="--step-profile: rays per step; several profile the record at each (the kernels' share "
                         "of a step grows with the batch where the host's work per step is fixed)")
    ap.add_argument("--scenes", help="comma-separated scenes whose fits and tasks run (default: all); finished "
                                     "runs in --work with the same settings are reused")
    ap.add_argument("--removal", action="store_true",
                    help="only the removal section: background strategies on the ground-truth scenes")
    ap.add_argument("--masks", action="store_true",
                    help="only the masks section: masks from two views, and removal with them")
    ap.add_argument("--effects", action="store_true",
                    help="only the effects section: removal with the object's shadow given as effect masks")
    ap.add_argument("--family", action="store_true",
                    help="only the removal family: the default judged on the scenes it was not tuned on")
    ap.add_argument("--spinnerf", action="store_true",
                    help="only SPIn-NeRF's protocol on family scenes in its layout (default: the check half)")
    ap.add_argument("--lpips-weights", metavar="DIR",
                    help="--spinnerf: folder with LPIPS weights (see mi_voldis/lpips.py; nothing is downloaded)")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", dest="sets",
                    help="--family: fit every scene with this setting too (a trial of a default, against the "
                         "default's report); needs its own --report")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--quiet", action="store_true", help="print nothing but errors (the children run quietly anyway)")
    args = ap.parse_args(argv)
    args.report = args.report or ("out/bench/quick" if args.quick else "reports")
    if args.lpips_weights and not args.spinnerf:
        ap.error("--lpips-weights is for --spinnerf")
    if args.sets:
        if not args.family:
            ap.error("--set is for --family (a trial of a default on the removal family)")
        for flag in ("report", "work"):  # a trial never writes over the default's report or refits its runs
            if os.path.realpath(getattr(args, flag)) == os.path.realpath(ap.get_default(flag) or "reports"):
                ap.error(f"--set: a trial goes in its own folders (give --{flag} DIR), not the default's")
        from mi_voldis.bench.family import load
        earlier = load(args.report)
        if earlier is not None and not earlier.get("sets"):
            ap.error(f"--set: {os.path.join(args.report, 'family.json')} is the default's report (no settings): "
                     "give the trial another --report")
        from mi_voldis.fit.config import FitConfig
        try:
            FitConfig.from_sources(None, args.sets)
        except ValueError as e:
            ap.error(str(e))
    os.environ["MI_VOLDIS_VARIANT"] = args.variant
    if args.step_profile:
        import json

        from mi_voldis.bench.throughput import step_profile
        try:
            batches = [int(b) for b in args.batch.split(",")]
            if min(batches) < 1:
                raise ValueError
        except ValueError:
            raise SystemExit(f"error: --batch {args.batch!r}: expected positive whole numbers, comma-separated"
                             ) from None
        # the record (adjoint replays the primal's lookup values) against reading the grid again, at the
        # first batch; the record at every other batch
        out = {"record": step_profile(rays=args.rays, batch=batches[0]),
               "no_record": step_profile(rays=args.rays, batch=batches[0], record=False)}
        if len(batches) > 1:
            out["by_batch"] = {str(b): out["record"] if b == batches[0] else step_profile(rays=args.rays, batch=b)
                               for b in batches}
        print(json.dumps(out, indent=1))
        return
    from mi_voldis.bench import report
    from mi_voldis.bench.family import run_family, write_family
    from mi_voldis.bench.run import run_all, run_effects, run_masks, run_removal, section_scenes
    from mi_voldis.bench.spinnerf import section as spinnerf_section
    from mi_voldis.io.run_folder import claim
    scenes = args.scenes.split(",") if args.scenes else None
    section = next((flag for flag in ("removal", "masks", "effects", "family", "spinnerf") if getattr(args, flag)),
                   "quick" if args.quick else "all")
    try:  # before anything runs: a bad --scenes or --report never costs a run its report
        section_scenes(section, scenes)
        claim(args.report, "bench")
    except ValueError as e:
        raise SystemExit(f"error: {e}") from None
    for flag, (measure, write) in {"removal": (run_removal, report.write_removal),
                                   "masks": (run_masks, report.write_masks),
                                   "effects": (run_effects, report.write_effects),
                                   "family": (run_family, write_family),
                                   "spinnerf": spinnerf_section(args.lpips_weights)}.items():
        if getattr(args, flag):  # one section alone, with its own report
            trial = {"sets": args.sets} if args.sets else {}  # only --family takes settings (checked above)
            results = measure(os.path.abspath(args.work), args.report, scenes, **trial)
            path = write(results, args.report, f"python scripts/bench.py --{flag}" +
                         (f" --scenes {args.scenes}" if args.scenes else "") +
                         "".join(f" --set {s}" for s in args.sets))
            if not args.quiet:
                print(path)
            return
    results = run_all(args.quick, os.path.abspath(args.work), args.report, scenes)
    command = "python scripts/bench.py" + (" --quick" if args.quick else "") + \
        (f" --scenes {args.scenes}" if args.scenes else "")
    report.write(results, args.report, command)
    if not args.quiet:
        print(os.path.join(args.report, "bench.md"))


def entry():
    """The console command (``[project.scripts]`` in pyproject.toml)."""
    sys.exit(run(main))
