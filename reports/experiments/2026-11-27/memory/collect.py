"""Gather finished runs' metrics into one JSON report (the rows reports/notes.md quotes).

    python reports/experiments/2026-11-27/memory/collect.py OUT.json "COMMAND" "NOTE" NAME=RUN ...
"""
import json
import sys

KEYS = ("held_out", "seconds", "grid", "bricks", "peak_rss_mib", "evaluated_samples_per_ray", "sh_choice", "space",
        "occupied_fraction")


def main(out, command, note, *pairs):
    runs = {}
    for pair in pairs:
        name, run = pair.split("=", 1)
        with open(f"{run}/metrics.json") as f:
            m = json.load(f)
        row = {k: m[k] for k in KEYS if k in m}
        row.update(steps=m["schedule"]["steps_full"], stages=m["schedule"]["stages"], plan=m["schedule"]["plan"])
        runs[name] = row
    try:
        with open(out, "x") as f:  # never over a report already written
            json.dump({"command": command, "note": note, "runs": runs}, f, indent=1)
    except FileExistsError:
        sys.exit(f"{out}: exists, not overwritten")


if __name__ == "__main__":
    main(*sys.argv[1:])
