#!/bin/sh
# #46: reports/experiments/2026-11-28/bg_trials/refit.sh with another dataset per scene to fit the background
# with (DATAROOT/familyNN, e.g. dilate_ds.py's), scored on the run's own
#   sh refit_masked.sh FITS WORK "SCENES" DATAROOT [--set KEY=VALUE ...]
set -e
FITS=$1; WORK=$2; SCENES=$3; DATAROOT=$4; shift 4
mkdir -p "$WORK/removal"
[ -e "$WORK/runs" ] || ln -s "$(realpath "$FITS")/runs" "$WORK/runs"
for s in $SCENES; do
  [ -f "$WORK/removal/family$s/guided/metrics.json" ] && continue
  .venv/bin/python -m mi_voldis.bench.strategies "$FITS/runs/family${s}_0" guided "$WORK/removal/family$s/guided" \
    "$DATAROOT/family$s" --refit "$@" > "$WORK/removal/family$s.log" 2>&1 || echo "family$s failed: $WORK/removal/family$s.log"
done
