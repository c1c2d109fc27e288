#!/bin/sh
# #46: the `guided` background refitted with SETS from the default fits of the removal family in FITS
# (`python scripts/bench.py --family --scenes familyNN --work FITS` keeps each fit with its checkpoints),
# one scene after another, into OUT/familyNN (metrics.json and the held-out views' backgrounds):
#   sh reports/experiments/2026-11-28/hull_fill_vertical/screen.sh FITS OUT "SCENES" [--set KEY=VALUE ...]
# e.g. FITS=/work/runs/fam OUT=/work/runs/trial/v0 "06 04 02" --set hull_fill_vertical=0
set -e
FITS=$1; OUT=$2; SCENES=$3; shift 3
mkdir -p "$OUT"
for s in $SCENES; do
  [ -f "$OUT/family$s/metrics.json" ] && continue
  .venv/bin/python -m mi_voldis.bench.strategies "$FITS/runs/family${s}_0" guided "$OUT/family$s" --refit "$@" \
    > "$OUT/family$s.log" 2>&1 || echo "family$s failed: $OUT/family$s.log"
done
