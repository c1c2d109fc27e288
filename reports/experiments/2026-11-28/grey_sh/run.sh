#!/bin/bash
# The commands behind reports/notes.md, "2026-11-28 (fourteenth session): grey view dependence". Run from the
# repository root, each alone on the machine; W: a scratch folder.
set -e
D=${DATA:-../shared/data}
W=${W:-runs}
T="/usr/bin/time -v"
# degree-1 colour with grey harmonics, alone and with garden's near_grad / contract_radius settings
$T python scripts/train.py $D/garden --out $W/garden_grey_ng1_cr05 --set sh_degree=1 --set sh_color=grey \
    --set near_grad=1 --set contract_radius=0.5 > $W/garden_grey_ng1_cr05.log 2>&1
$T python scripts/train.py $D/garden --out $W/garden_grey_ng1_cr05_m13 --set sh_degree=1 --set sh_color=grey \
    --set near_grad=1 --set contract_radius=0.5 --set minutes=13 > $W/garden_grey_ng1_cr05_m13.log 2>&1
for c in garden statue horns; do
  $T python scripts/train.py $D/$c --out $W/${c}_grey --set sh_degree=1 --set sh_color=grey > $W/${c}_grey.log 2>&1
done
python reports/experiments/2026-11-28/distortion/collect.py reports/captures/cpu_2026-11-28_grey_sh1.json \
  "python scripts/train.py ../shared/data/CAPTURE --out RUN --set sh_degree=1 --set sh_color=grey [--set near_grad=1 --set contract_radius=0.5]" \
  "each alone on the 2 cores" garden_grey=$W/garden_grey garden_grey_ng1_cr05=$W/garden_grey_ng1_cr05 \
  statue_grey=$W/statue_grey horns_grey=$W/horns_grey garden_grey_ng1_cr05_m13=$W/garden_grey_ng1_cr05_m13
# per-view comparison with the RGB rows of cpu_2026-11-28_garden_near_grad_sh1.json (garden_ng1_sh1_cr05, _m8)
python reports/experiments/2026-11-28/garden_views.py rgb128=$W/garden_ng1_sh1_cr05 grey160=$W/garden_grey_ng1_cr05 \
  rgb176_8g=$W/garden_ng1_sh1_cr05_m8 > reports/experiments/2026-11-28/grey_sh/garden_views.txt
python reports/experiments/2026-11-28/grey_sh/preview_sheet.py reports/captures/garden_grey_views.png $D/garden 0,16 \
  $W/garden_ng1_sh1_cr05 $W/garden_grey_ng1_cr05 $W/garden_ng1_sh1_cr05_m8
# memory a vertex at the three colour layouts, same schedule (64 -> 160, 450 steps)
for v in "d0:sh_degree=0" "grey:sh_degree=1 sh_color=grey" "rgb:sh_degree=1"; do
  name=${v%%:*}; sets=""; for s in ${v#*:}; do sets="$sets --set $s"; done
  python reports/experiments/2026-11-27/memory/phase_peaks.py -- $D/garden --out $W/peak_garden_$name \
    --set 'resolution_schedule=[[0,64],[200,160]]' --set steps_full=450 $sets > $W/peak_garden_$name.log 2>&1
done
python reports/experiments/2026-11-28/grey_sh/per_vertex.py $W/peak_garden_d0 $W/peak_garden_grey $W/peak_garden_rgb \
  > reports/experiments/2026-11-28/grey_sh/per_vertex.txt
# the 'auto' rule's trials with grey harmonics, full resolution and low-passed (a worktree with sh_trial.diff applied)
for c in garden horns statue fern; do
  WT=$WT reports/experiments/2026-11-28/grey_sh/trial_only.sh $D/$c $W/trial_$c $W/trial_$c.log --set sh_color=grey
done
# the removal family's tuning half fitted at degree 1, grey (against reports/family.json)
python scripts/bench.py --family --work $W/fam --report $W/fam_grey_tuning \
  --scenes family00,family01,family02,family03,family04,family05,family06,family07,family08,family09 \
  --set sh_degree=1 --set sh_color=grey
