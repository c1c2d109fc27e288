#!/bin/sh
# The 'auto' degree trial's gain under today's defaults (the gate on) for each DATASET: starts the default fit,
# stops it once the trial's note is printed, and prints that note. Run from the checkout:
#   sh reports/experiments/2026-11-29/sh_gate/trials.sh OUT DATASET...
# (the gains of trials_gated.txt: room and random0-4 made by scripts/make_dataset.py, the captures in
# ../shared/data, the family's datasets as scripts/bench.py --family makes them)
out=$1; shift
mkdir -p "$out"
for data in "$@"; do
  name=$(basename "$data")
  .venv/bin/python scripts/train.py "$data" --out "$out/run_$name" > "$out/train_$name.log" 2>&1 &
  pid=$!
  while kill -0 $pid 2>/dev/null; do
    if tr '\r' '\n' < "$out/train_$name.log" | grep -a -q "colour of SH degree"; then kill $pid; break; fi
    sleep 3
  done
  echo "$name $(tr '\r' '\n' < "$out/train_$name.log" | grep -a 'colour of SH degree')"
done
