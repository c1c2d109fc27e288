"""The default fit with the memory model's bytes a stored vertex set to another figure (a trial of
``mi_voldis.fit.schedule.BYTES_PER_VERTEX`` before it changes in the package).

    python reports/experiments/2026-12-06e/bytes_trial.py BYTES DATASET --out RUN [train.py's options]
"""
import os
import sys

sys.path.insert(0, os.getcwd())
from mi_voldis.fit import schedule  # noqa: E402
from voldis_cli.train import entry  # noqa: E402

schedule.BYTES_PER_VERTEX = int(sys.argv.pop(1))
entry()
