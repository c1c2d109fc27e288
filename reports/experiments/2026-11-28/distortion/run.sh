#!/bin/sh
# How the figures of reports/notes.md "2026-11-28 (twelfth session): the distortion weight, degree-1 colour
# with near_grad on garden, two prior variants" were made; each fit alone on the 2 cores. W: a scratch folder
# outside the repo.
set -eu
W=${W:-/tmp/distortion}
PY=${PYTHON:-.venv/bin/python}
T="/usr/bin/time -v"
# the full phase's distortion weight (default 0.01)
$T $PY scripts/train.py ../shared/data/fern --out $W/fern_dist05 --set distortion=0.05 > $W/fern_dist05.log 2>&1
$T $PY scripts/train.py ../shared/data/fern --out $W/fern_dist02 --set distortion=0.02 > $W/fern_dist02.log 2>&1
$T $PY scripts/train.py ../shared/data/statue --out $W/statue_dist02 --set distortion=0.02 > $W/statue_dist02.log 2>&1
$T $PY scripts/train.py ../shared/data/statue --out $W/statue_dist005 --set distortion=0.005 > $W/statue_dist005.log 2>&1
$PY reports/experiments/2026-11-28/distortion/collect.py reports/captures/cpu_2026-11-28_distortion.json \
    "python scripts/train.py ../shared/data/CAPTURE --out RUN --set distortion=D" "runs named CAPTURE_D" \
    fern_0.02=$W/fern_dist02 fern_0.05=$W/fern_dist05 statue_0.02=$W/statue_dist02 statue_0.005=$W/statue_dist005
# garden: near-camera gradient scaling with degree-1 colour, at the default memory bound, at 8 GiB, with contract_radius 0.5
$T $PY scripts/train.py ../shared/data/garden --out $W/garden_ng1_sh1 --set sh_degree=1 --set near_grad=1 \
    > $W/garden_ng1_sh1.log 2>&1
$T $PY scripts/train.py ../shared/data/garden --out $W/garden_ng1_sh1_m8 --set sh_degree=1 --set near_grad=1 \
    --set max_memory_gib=8 > $W/garden_ng1_sh1_m8.log 2>&1
$T $PY scripts/train.py ../shared/data/garden --out $W/garden_ng1_sh1_cr05 --set sh_degree=1 --set near_grad=1 \
    --set contract_radius=0.5 > $W/garden_ng1_sh1_cr05.log 2>&1
$T $PY scripts/train.py ../shared/data/garden --out $W/garden_ng1_sh1_cr05_m8 --set sh_degree=1 --set near_grad=1 \
    --set contract_radius=0.5 --set max_memory_gib=8 > $W/garden_ng1_sh1_cr05_m8.log 2>&1
$PY reports/experiments/2026-11-28/distortion/collect.py reports/captures/cpu_2026-11-28_garden_near_grad_sh1.json \
    "python scripts/train.py ../shared/data/garden --out RUN --set sh_degree=1 --set near_grad=1 [--set max_memory_gib=8] [--set contract_radius=0.5]" \
    "garden_ng1_sh1: 4 GiB (default); garden_ng1_sh1_m8: 8 GiB" \
    garden_ng1_sh1=$W/garden_ng1_sh1 garden_ng1_sh1_m8=$W/garden_ng1_sh1_m8 garden_ng1_sh1_cr05=$W/garden_ng1_sh1_cr05 \
    garden_ng1_sh1_cr05_m8=$W/garden_ng1_sh1_cr05_m8
# the sheet reports/captures/garden_near_grad_sh1_views.png: columns the default, near_grad 1, near_grad 1 +
# degree 1 at 4 GiB and at 8 GiB; rows the full layer of held-out views 0 and 16, then view 16's depth; from the
# runs' previews/view{000,016}_{full,depth}.png, halved
# the prior variants on family06 (trial code outside the repo: see the notes) were refitted with
#   reports/experiments/2026-11-28/color_fill/rows.py OUT $FAMILY_WORK/runs/family06_0 [--set bg_strategy=clear | --set object_alpha=0.05]
# fern_distortion_view008.png: held-out view 8 of the default (fern_h of cpu_2026-11-27_step_auto.json), 0.02 and 0.05; rows previews/view008_full.png and view008_depth.png, at 2/3 size
# garden_near_grad_sh1_cr05_m8_views.png: held-out views 8 and 16, columns garden's default run, garden_ng1_sh1_m8,
# garden_ng1_sh1_cr05_m8 (previews/view{008,016}_full.png, halved)
