#!/bin/bash
# Runs a fit from the checkout in $WT (the instrumented choose_sh_degree of sh_trial.diff applied) until both
# of the 'auto' rule's trials have printed their SHTRIAL lines, then stops it: the rule's inputs without the fit.
#   WT=/tmp/wt reports/experiments/2026-11-28/grey_sh/trial_only.sh DATASET OUT LOG [--set k=v ...]
set -u
data=$1; out=$2; log=$3; shift 3
if [ -e "$log" ]; then echo "$log: exists; not overwritten" >&2; exit 1; fi
(cd "$WT" && exec .venv/bin/python scripts/train.py "$data" --out "$out" "$@") > "$log" 2>&1 &
pid=$!
while kill -0 $pid 2>/dev/null; do
  if [ "$(grep -c '^SHTRIAL perview8' "$log")" -ge 2 ]; then kill $pid; wait $pid 2>/dev/null; break; fi
  sleep 2
done
grep '^SHTRIAL' "$log"
