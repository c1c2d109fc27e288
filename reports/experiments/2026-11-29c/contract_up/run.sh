#!/bin/sh
# #42 / #46: a 360-degree capture's contracted cube levelled by the cameras' up (a trial, not kept). Run from a
# copy of the package with contract_up.diff applied (git apply), which adds the setting contract_up (default true).
# Each garden fit alone on the 2 cores; the removal and the tilted fits ran beside each other (no timings).
# W: a scratch folder outside the repo. Outputs: garden.json, tilt08.json, garden_removal_levelled_metrics.json
# (the default's removal row: reports/garden_removal.md), the two PNG sheets.
set -eu
W=${W:-/tmp/contract_up}
PY=${PYTHON:-.venv/bin/python}
E=reports/experiments/2026-11-29c/contract_up
mkdir -p $W
# garden, the default command (levelled now), and with the world's axes as before
/usr/bin/time -v $PY scripts/train.py ../shared/data/garden --out $W/garden --keep-checkpoints
/usr/bin/time -v $PY scripts/train.py ../shared/data/garden --out $W/garden_axes --keep-checkpoints --set contract_up=false
# garden's vase removed with reports/garden_removal.md's box masks (DATA: its masked copy, made as that file says)
$PY -m mi_voldis.bench.strategies $W/garden guided $W/garden_removal ${GARDEN_MASKED:-$W/garden_masked}
# three removal-family orbits as tilted 360-degree captures (19 degrees), levelled or not
for s in 08; do  # 12 and 16 were started and stopped for time
  $PY $E/tilted.py ${FAMILY:-/work/runs/fam/data}/family$s $W/tilt$s 19
  $PY scripts/train.py $W/tilt$s --out $W/tilt${s}_up
  $PY scripts/train.py $W/tilt$s --out $W/tilt${s}_axes --set contract_up=false
done
