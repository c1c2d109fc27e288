"""Seconds inside a fit's full phase spent outside its steps, from a py-spy raw profile of the whole run
(`py-spy record -r 10 -f raw`): checkpoints (`FitState.save`), the held-out evaluations for the log
(`held_out_psnr`'s `evaluate`), the moving average (`FieldFit.average`), and the rest of the phase.

    python full_phase_seconds.py FILE [FILE ...]
"""
import collections
import sys

PARTS = {"checkpoints": "FitState.save", "log evaluations": "evaluate (mi_voldis/fit/train.py",
         "moving average": "FieldFit.average", "stage changes": "refine (mi_voldis/fit/fields.py",
         "occupancy updates": "FieldFit.update_occupancy"}

for path in sys.argv[1:]:
    parts, total = collections.Counter(), 0
    for line in open(path):
        stack, _, n = line.rstrip().rpartition(" ")
        if "fit_full" not in stack:
            continue
        total += int(n)
        for name, frame in PARTS.items():
            if frame in stack:
                parts[name] += int(n)
                break
    print(f"{path}: full phase {total / 10:.1f} s; " + ", ".join(f"{k} {parts[k] / 10:.1f} s" for k in PARTS))
