#!/bin/sh
# #42: the sh_degree 'auto' trial of each capture or family dataset, read off the default command's own note
# ("note: colour of SH degree ... (the trial fits' validation views: +X dB at degree 1 ...)"), the fit then
# stopped. Run from the repository root:
#   sh reports/experiments/2026-11-29/sh_trial/trials.sh OUT DATASET...
# SET: extra settings for every fit, e.g. SET="--set near_grad=1" (2026-11-29d/sh_trial_near_grad)
# (the 2026-11-29 figures in trials.txt came from an instrumented copy that printed both the colour-only
# trial of before and the joint trial that replaced it, "JOINT TRIAL ... gain")
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
