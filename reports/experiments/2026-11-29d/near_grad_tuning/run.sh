#!/bin/sh
# #46: near_grad 1 on the tuning half's two orbits not yet run under today's code (family00, family08), each scene's
# data copied into its own work folder first, the two fits side by side (no timings). compare_familyNN.txt: the rows
# against the committed reports/family.json, by reports/experiments/2026-11-28/family_tv2/compare.py.
set -eu
W=${W:-/tmp/near_grad_tuning}
PY=${PYTHON:-.venv/bin/python}
for s in 08 00; do
  mkdir -p $W/ng$s/data && cp -r ${FAMILY:-/work/runs/fam/data}/family$s $W/ng$s/data/
  $PY scripts/bench.py --family --scenes family$s --work $W/ng$s --report $W/ng$s/report --set near_grad=1
  $PY reports/experiments/2026-11-28/family_tv2/compare.py $W/ng$s
done
