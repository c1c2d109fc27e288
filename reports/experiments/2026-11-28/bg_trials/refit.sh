#!/bin/sh
# #46: the `guided` background refitted with today's code (and SETS) from the default fits of the removal family
# kept in FITS (runs/familyNN_0 with checkpoints), one scene after another, into WORK/removal/SCENE/guided;
# WORK/runs links to FITS so that reports/experiments/2026-11-28/family_tv2/compare.py WORK reads them.
#   sh reports/experiments/2026-11-28/bg_trials/refit.sh FITS WORK "SCENES" [--set KEY=VALUE ...]
set -e
FITS=$1; WORK=$2; SCENES=$3; shift 3
mkdir -p "$WORK/removal"
[ -e "$WORK/runs" ] || ln -s "$(realpath "$FITS")/runs" "$WORK/runs"
for s in $SCENES; do
  [ -f "$WORK/removal/family$s/guided/metrics.json" ] && continue
  .venv/bin/python -m mi_voldis.bench.strategies "$FITS/runs/family${s}_0" guided "$WORK/removal/family$s/guided" \
    --refit "$@" > "$WORK/removal/family$s.log" 2>&1 || echo "family$s failed: $WORK/removal/family$s.log"
done
