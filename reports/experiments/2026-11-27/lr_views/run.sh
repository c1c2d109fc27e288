#!/bin/sh
# #42 item 4 / #46: learning rates per brick by the training views that observe it (lr_views), screened on
# the removal family against the committed default's fits (out/fam_split/runs/familyK_0, made by
# `python scripts/bench.py --family --work out/fam_split`). One fit at a time, the default command plus
# the settings given:
#   SCENES="06 02 04 00 09 05 01 03 07 08" sh reports/experiments/2026-11-27/lr_views/run.sh p1 lr_views=1
#   python reports/experiments/2026-11-27/lr_views/compare.py p1 > results.json
set -eu
name=$1; shift
sets=""; for s in "$@"; do sets="$sets --set $s"; done
PY=${PYTHON:-.venv/bin/python}
for k in $SCENES; do
  run=out/lrv/family${k}_$name
  [ -f $run/metrics.json ] || $PY scripts/train.py out/bench/data/family$k --out $run --keep-checkpoints --quiet $sets \
      > out/lrv/fit_${k}_$name.log 2>&1
  echo "family$k $name $(date)"
done
# the removal bench's rows from each fit (its background refitted, scored as reports/removal.md scores it):
#   ROWS=1 SCENES=... sh run.sh p1 lr_views=1
if [ "${ROWS:-0}" = 1 ]; then
  for k in $SCENES; do
    row=out/lrv/removal/family$k/$name
    [ -f $row/metrics.json ] || $PY -m mi_voldis.bench.strategies out/lrv/family${k}_$name guided $row --refit \
        > out/lrv/row_${k}_$name.log 2>&1
    echo "row family$k $name $(date)"
  done
fi
