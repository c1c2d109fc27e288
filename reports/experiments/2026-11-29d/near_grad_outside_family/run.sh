#!/bin/sh
# #42 / #46: near_grad 1 outside the family: the demo's scene (the tabletop dataset `make demo` writes to
# out/demo/data/tabletop) and garden, whose near_grad fit then gets the vase's removal with the box masks of
# reports/garden_removal.md (GARDEN_MASKED: the masked copy that report's commands make). The two fits ran side by
# side (no timings); the removal ran alone.
set -eu
W=${W:-/tmp/near_grad_outside_family}
PY=${PYTHON:-.venv/bin/python}
$PY scripts/train.py out/demo/data/tabletop --out $W/tabletop_ng1 --quiet --set near_grad=1
$PY scripts/train.py ../shared/data/garden --out $W/garden_ng1 --keep-checkpoints --quiet --set near_grad=1
$PY -m mi_voldis.bench.strategies $W/garden_ng1 guided $W/garden_ng1_removal ${GARDEN_MASKED:?the masked copy of garden}
