#!/bin/sh
# What a one-voxel step saves a training step on a fine grid: the same explicit plan of capture DATASET at half
# a voxel and at one, one fit after the other (run it alone: the step seconds are the measurement), then the
# last stage's median seconds and samples a step of each (step_cost.py).
#
#   sh reports/experiments/2026-11-27/step/step_cost.sh DATASET OUTDIR SCHEDULE STEPS
#   sh reports/experiments/2026-11-27/step/step_cost.sh ../shared/data/statue /tmp/sc \
#       '[[0,64],[300,128],[600,232],[1000,464]]' 1500
set -e
DS=$1; OUT=$2; SCHED=$3; N=$4
if [ -e "$OUT" ]; then echo "$OUT: exists, not overwritten" >&2; exit 1; fi
mkdir -p "$OUT"
for s in 0.5 1.0; do
  python scripts/train.py "$DS" --out "$OUT/step_$s" --set "resolution_schedule=$SCHED" --set steps_full="$N" \
    --set steps_bg=0 --set sh_degree=0 --set step_voxels=$s > "$OUT/step_$s.log" 2>&1
done
python reports/experiments/2026-11-27/step/step_cost.py "$OUT/step_0.5" "$OUT/step_1.0"
