"""The default background row refitted from finished family fits, and its margins (the #46 protocol).

    python reports/experiments/2026-11-28/color_fill/rows.py OUT RUN... [--set KEY=VALUE ...]

Each RUN (a fit kept with --keep-checkpoints, e.g. a `bench.py --family` work folder's runs/familyNN_0)
has its background refitted with `guided` and the settings given (`mi_voldis.bench.strategies ... --refit`)
into OUT/<run name>; a folder already holding a refit's metrics.json is read, not refitted. Prints one line
per run: in-mask PSNR, margin over max(Telea, Navier-Stokes), coverage IoU, consistency, haze in / outside.
"""
import json
import os
import subprocess
import sys

from refitted import split_sets


def margin_line(metrics, name):
    m = metrics["methods"]
    v = m["volume"]
    best = max(m[k]["psnr_mask"] for k in ("telea", "ns"))
    return (f"{name:12s} mask {v['psnr_mask']:.2f} margin {v['psnr_mask'] - best:+.2f} "
            f"iou {v['fg_coverage_iou']:.3f} cons {v['consistency_psnr']:.2f} "
            f"haze {v['bg_haze_mask']:.3f}/{v['bg_haze_outside']:.3f}")


def main(argv):
    sets, plain = split_sets(argv)
    if len(plain) < 2:
        raise SystemExit(__doc__.strip().splitlines()[2].strip())
    out, runs = plain[0], plain[1:]
    for run in runs:
        name = os.path.basename(os.path.normpath(run))
        folder = os.path.join(out, name)
        done = os.path.join(folder, "metrics.json")
        if not os.path.exists(done):
            args = [sys.executable, "-m", "mi_voldis.bench.strategies", run, "guided", folder, "--refit"]
            for s in sets:
                args += ["--set", s]
            os.makedirs(out, exist_ok=True)
            path = os.path.join(out, name + ".log")
            try:
                log = open(path, "x")  # a log left by an earlier try stays as it is
            except FileExistsError:
                raise SystemExit(f"error: {path}: exists (an earlier refit's log): give another OUT") from None
            with log:
                if subprocess.call(args, stdout=log, stderr=subprocess.STDOUT):
                    raise SystemExit(f"error: {run}: the refit failed (see {path})")
        with open(done) as f:
            print(margin_line(json.load(f), name), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
