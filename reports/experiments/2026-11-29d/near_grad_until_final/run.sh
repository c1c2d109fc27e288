#!/bin/sh
# #42 / #46: near_grad 1 in the full phase's stages before the last, off on the final grid (trial.diff, applied to a
# copy of the package and switched on by NG_UNTIL_FINAL=1). garden with the default command otherwise; family02 by
# the family bench. Both ran side by side (no timings). Outputs: garden_views.txt (per view, against today's default
# fit), compare_family02.txt (against the committed reports/family.json), the sheet
# garden_views48_160_32_default_vs_until_final.png (columns: photo, default, this trial) by
# reports/experiments/2026-11-28/near_grad/garden_sheet.py on `scripts/render.py RUN/scene.xml --split test` renders.
set -eu
W=${W:-/tmp/near_grad_until_final}
PY=${PYTHON:-.venv/bin/python}
mkdir -p $W/ngu02/data && cp -r ${FAMILY:-/work/runs/fam/data}/family02 $W/ngu02/data/
NG_UNTIL_FINAL=1 $PY scripts/train.py ../shared/data/garden --out $W/garden_ngu --quiet --set near_grad=1
NG_UNTIL_FINAL=1 $PY scripts/bench.py --family --scenes family02 --work $W/ngu02 --report $W/ngu02/report --set near_grad=1
$PY reports/experiments/2026-11-28/family_tv2/compare.py $W/ngu02
