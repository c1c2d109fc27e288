#!/bin/bash
# The same short fixed-plan fern fit, alternately on two checkouts, two rounds (the machine, not the code?).
# usage: speed.sh OLD_CHECKOUT NEW_CHECKOUT OUT_DIR [PYTHON]   (absolute paths; OLD: e.g. `git worktree add DIR 70bbacb`)
old=$1 new=$2 out=$3 py=${4:-python}
data=${MI_VOLDIS_CAPTURES:-../shared/data}/fern
data=$(cd "$data" && pwd)
sets=(--set minutes=null --set steps_full=300 --set steps_bg=1 --set "resolution_schedule=[[0,64],[150,256]]"
      --set eval_every=100000)
for round in 1 2; do
  for tree in old new; do
    dir=$old; [ $tree = new ] && dir=$new
    (cd "$dir" && PYTHONPATH="$dir" "$py" scripts/train.py "$data" --out "$out/speed_${tree}_$round" --quiet "${sets[@]}")
  done
done
