#!/usr/bin/env bash
# The keep_seen variants of the notes ("keep_seen on the removal family's tuning half"): each tuning scene's
# background refitted from its bench run (out/bench, python scripts/bench.py --family) with one setting changed.
cd "$(dirname "$0")/../../../.."

for scene in family00 family01 family03 family05 family07 family08 family09 family02 family04 family06; do
  for v in "keep_seen=false" "keep_seen_gap=3" "keep_seen_gap=2"; do
    tag=$(echo $v | tr '=' '_')
    [ -f out/exp/${scene}_$tag/metrics.json ] && continue
    .venv/bin/python -m mi_voldis.bench.strategies out/bench/runs/${scene}_0 guided out/exp/${scene}_$tag --set $v > out/exp/${scene}_$tag.log 2>&1
    echo "$scene $v done $(date +%T)"
  done
done
