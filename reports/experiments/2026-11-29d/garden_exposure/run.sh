#!/bin/sh
# #42: garden with per-image exposure (the default command plus --set exposure=true), alone and with near_grad 1;
# the two fits ran side by side (no timings). garden_views.txt: per held-out view against today's default fit
# (reports/experiments/2026-11-28/garden_views.py); the sheet: rows frames 137, 103, 153, 177 of the test split,
# columns photo, default, exposure, exposure + near_grad 1 (reports/experiments/2026-11-28/near_grad/garden_sheet.py
# on `scripts/render.py RUN/scene.xml --cameras ../shared/data/garden --split test --layer full` renders).
set -eu
W=${W:-/tmp/garden_exposure}
PY=${PYTHON:-.venv/bin/python}
$PY scripts/train.py ../shared/data/garden --out $W/garden_exp --quiet --set exposure=true
$PY scripts/train.py ../shared/data/garden --out $W/garden_exp_ng1 --quiet --set exposure=true --set near_grad=1
