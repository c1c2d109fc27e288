#!/bin/bash
# #46 trial: a told run's `guided` background refitted with the trial settings of fill_trial.diff (applied to a
# clone of fc9b729 at TRIAL), `python -m mi_voldis.bench.strategies RUN guided OUT --refit --set ...`.
#   fill_refit.sh TRIAL RUN OUT [--set NAME=VALUE ...]
# OUT must not exist (bench.strategies makes it).
set -e
TRIAL=$1; RUN=$2; OUT=$3; shift 3
[ -e "$OUT" ] && { echo "error: $OUT exists; give another OUT" >&2; exit 2; }
cd "$TRIAL"
PYTHONPATH="$TRIAL" python -m mi_voldis.bench.strategies "$RUN" guided "$OUT" --refit "$@" > "$OUT.log" 2>&1
