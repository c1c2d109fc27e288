#!/bin/sh
# #42: the sh_degree 'auto' trial of each dataset under extra settings (SET, e.g. "--set near_grad=1"), read off the
# default command's own note ("note: colour of SH degree ... +X dB at degree 1 ..."), the fit then stopped.
# The same as reports/experiments/2026-11-29/sh_trial/trials.sh with the settings passed on. From the repository root:
#   SET="--set near_grad=1" sh reports/experiments/2026-11-29d/sh_trial_near_grad/trials.sh OUT DATASET...
OUT=$1; shift
mkdir -p "$OUT"
for d in "$@"; do
  name=$(basename "$d")
  # shellcheck disable=SC2086
  .venv/bin/python scripts/train.py "$d" --out "$OUT/$name" $SET > "$OUT/$name.log" 2>&1 &
  pid=$!
  while kill -0 $pid 2>/dev/null; do
    if grep -q "note: colour of SH degree" "$OUT/$name.log"; then kill $pid; break; fi
    sleep 5
  done
  echo "$name: $(grep 'note: colour of SH degree' "$OUT/$name.log")"
done
