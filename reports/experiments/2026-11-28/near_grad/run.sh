#!/bin/sh
# How the near_grad figures of reports/notes.md ("Near-camera gradient scaling", 2026-11-28) were made; each
# fit alone on the 2 cores unless the notes say otherwise. W: a scratch folder outside the repo.
set -eu
W=${W:-/tmp/near_grad}
PY=${PYTHON:-.venv/bin/python}
# garden and the statue, the default command plus the setting (the default's garden run beside them)
/usr/bin/time -v $PY scripts/train.py ../shared/data/garden --out $W/garden_default
for r in 1 0.5; do
  /usr/bin/time -v $PY scripts/train.py ../shared/data/garden --out $W/garden_ng$r --set near_grad=$r
done
/usr/bin/time -v $PY scripts/train.py ../shared/data/statue --out $W/statue_ng1 --set near_grad=1
/usr/bin/time -v $PY scripts/train.py ../shared/data/garden --out $W/garden_ng1_sp0 --set near_grad=1 --set sparsity=0
/usr/bin/time -v $PY scripts/train.py ../shared/data/garden --out $W/garden_ng1_tvhalf --set near_grad=1 \
    --set tv_density=5e-4 --set tv_color=5e-5
$PY reports/experiments/2026-11-28/garden_views.py default=$W/garden_default near_grad1=$W/garden_ng1 \
    near_grad05=$W/garden_ng0.5 near_grad1_sparsity0=$W/garden_ng1_sp0 near_grad1_tv_half=$W/garden_ng1_tvhalf
    # (garden_views.txt here)
# the renders and the contact sheet (rows views 48, 160, 32)
for run in $W/garden_default $W/garden_ng0.5 $W/garden_ng1; do
  $PY scripts/render.py $run/scene.xml --out $W/render_$(basename $run) --cameras ../shared/data/garden --split test --layer full
done
# the removal family: tuning scenes, then the check half's first scenes (stopped after family12's fit)
$PY scripts/bench.py --family --scenes family06,family00,family04,family02 --set near_grad=1 --work $W/w1 --report $W/r1
$PY scripts/bench.py --family --scenes family06,family00,family04,family02 --set near_grad=0.5 --work $W/w05 --report $W/r05
# the rows again from the R = 1 fits, with near_grad in the full phase only (63b14fa)
for k in 10 02 06 04 00; do
  $PY -m mi_voldis.bench.strategies $W/w1/runs/family${k}_0 guided $W/w1fo/removal/family$k/guided --refit
done
mkdir -p $W/w1fo/runs; for k in 10 02 06 04 00; do ln -s $W/w1/runs/family${k}_0 $W/w1fo/runs/; done
for w in w1 w1fo w05; do $PY reports/experiments/2026-11-28/family_tv2/compare.py $W/$w; done  # compare_*.txt here
$PY reports/experiments/2026-11-28/near_grad/reach.py ../shared/data/fern ../shared/data/horns ../shared/data/statue \
    ../shared/data/garden   # reach.txt here
