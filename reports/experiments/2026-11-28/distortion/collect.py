"""Rows of capture fits, each run's metrics.json with the wall clock and peak RSS of its ``/usr/bin/time -v``
log, into one JSON (the layout of reports/captures/cpu_*.json).

    python reports/experiments/2026-11-28/distortion/collect.py OUT.json "COMMAND" "NOTE" NAME=RUN[:LOG] ...

LOG defaults to RUN.log (train.py's output followed by time's report). OUT.json may exist only as a file this
script wrote (it is then replaced), never as anything else."""
import json
import os
import re
import sys

KEEP = ("held_out", "per_view", "seconds", "grid", "bricks", "peak_rss_mib", "evaluated_samples_per_ray", "sh_choice",
        "space", "occupied_fraction", "schedule")


def wall(log):
    """Seconds of '(h:mm:ss or m:ss): ...' in a time -v report, None without one."""
    m = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([\d:.]+)", log)
    if not m:
        return None
    parts = [float(p) for p in m.group(1).split(":")]
    return sum(p * 60 ** k for k, p in enumerate(reversed(parts)))


def ours(path):
    """Whether ``path`` is absent or a rows file this script wrote (the only thing it may replace)."""
    if not os.path.lexists(path):
        return True
    try:
        with open(path) as f:
            return os.path.isfile(path) and set(json.load(f)) == {"command", "note", "runs"}
    except (OSError, ValueError):
        return False


def main(argv):
    if len(argv) < 4:
        raise SystemExit(__doc__.strip().splitlines()[3].strip())
    out, command, note, pairs = argv[0], argv[1], argv[2], argv[3:]
    if not ours(out):
        raise SystemExit(f"collect.py: {out}: exists and is not a rows file of this script; give a new file")
    runs = {}
    for pair in pairs:
        name, _, spec = pair.partition("=")
        run, _, log = spec.partition(":")
        log = log or run.rstrip("/") + ".log"
        try:
            with open(f"{run}/metrics.json") as f:
                m = json.load(f)
            with open(log) as f:
                text = f.read()
        except (OSError, ValueError) as e:
            raise SystemExit(f"collect.py: {name}: {getattr(e, 'filename', None) or run}: "
                             f"{getattr(e, 'strerror', None) or e}")
        row = {k: m[k] for k in KEEP if k in m}
        row["wall_seconds"] = wall(text)
        runs[name] = row
        print(f"{name}: {m['held_out']['psnr']:.3f} dB, grid {m['grid']['full'][0]}^3, "
              f"{'no' if row['wall_seconds'] is None else format(row['wall_seconds'], '.0f')} s wall, "
              f"{m['peak_rss_mib'] / 1024:.2f} GiB, "
              f"{m['evaluated_samples_per_ray']:.0f} samples/ray, haze {m['held_out'].get('haze', float('nan')):.3f}")
    with open(out, "w") as f:
        json.dump({"command": command, "note": note, "runs": runs}, f, indent=1)


if __name__ == "__main__":
    main(sys.argv[1:])
