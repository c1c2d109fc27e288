#!/bin/sh
# #46: near_grad 1 on the check half's orbit and arc scenes (the hand-held and forward rigs look at their scene
# from beyond its reach, so it leaves them as they are: reports/notes.md, 2026-11-28). Each scene's data copied
# into its own work folder first; the fits ran two at a time (no timings). compare_near_grad1.txt: the rows
# against the committed reports/family.json, by reports/experiments/2026-11-28/family_tv2/compare.py.
set -eu
W=${W:-/tmp/near_grad_check}
PY=${PYTHON:-.venv/bin/python}
for s in 16 14 12 18 04 06; do  # 04 and 06: the tuning half, under today's code
  mkdir -p $W/ng$s/data && cp -r ${FAMILY:-/work/runs/fam/data}/family$s $W/ng$s/data/
  $PY scripts/bench.py --family --scenes family$s --work $W/ng$s --report $W/ng$s/report --set near_grad=1
  $PY reports/experiments/2026-11-28/family_tv2/compare.py $W/ng$s
done
