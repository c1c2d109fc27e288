#!/bin/sh
# #46: the removal family's backgrounds refitted from their default full fields with the prior's weight changed
# (a background-only setting: `python -m mi_voldis.bench.strategies RUN guided OUT --refit --set prior_weight=W`).
#   sh reports/experiments/2026-11-29b/prior_weight/run.sh RUNS OUT W SCENE...
# RUNS: the family's default fits (RUNS/familyNN_0, fitted with --keep-checkpoints by `bench.py --family`);
# OUT/pwW/familyNN: each refit's metrics.json and previews. Two scenes at a time.
runs=$1; out=$2; w=$3; shift 3
for s in "$@"; do
  echo "$s"
done | xargs -P 2 -I{} sh -c ".venv/bin/python -m mi_voldis.bench.strategies $runs/{}_0 guided $out/pw$w/{} --refit --set prior_weight=$w > $out/pw$w/{}.log 2>&1"
