#!/bin/sh
# Item 4 of #42, a first screen: fitting settings side by side on one capture at a short explicit plan
# (64 -> 128 -> 256, 1500 steps), two fits at a time; held-out PSNR from each run's metrics.json.
#   sh reports/experiments/2026-11-27/screen/screen.sh DATASET OUT
set -eu
DATA=$1
OUT=$2
PY=${PYTHON:-.venv/bin/python}
PLAN="--set resolution_schedule=[[0,64],[200,128],[400,256]] --set steps_full=1500 --set sh_degree=0"
mkdir -p "$OUT"
run() {  # NAME SETTINGS...
    name=$1; shift
    [ -f "$OUT/$name/metrics.json" ] || $PY scripts/train.py "$DATA" --out "$OUT/$name" --quiet $PLAN "$@" \
        > "$OUT/$name.log" 2>&1
}
run base & run tv10 --set tv_density=1e-3 --set tv_color=1e-4; wait
run dist0.1 --set distortion=0.001 & run lr2 --set lr_density=0.2 --set lr_color=0.1; wait
run lr2tv10 --set lr_density=0.2 --set lr_color=0.1 --set tv_density=1e-3 --set tv_color=1e-4 &
run lr4 --set lr_density=0.4 --set lr_color=0.2; wait
for m in "$OUT"/*/metrics.json; do
    $PY -c "import json, sys; m = json.load(open(sys.argv[1])); print(sys.argv[1].split('/')[-2], round(m['held_out']['psnr'], 3), round(m['held_out']['haze'], 3), round(m['seconds']['fit']), round(m['evaluated_samples_per_ray']))" "$m"
done
