#!/bin/bash
# The commands behind reports/notes.md, "2026-11-30 (twenty-eighth session)". Run from the repository root; W: a
# scratch folder; D: the captures. Every fit ran alone on the 2 cores unless said.
set -e
D=${DATA:-../shared/data}
W=${W:-runs}
E=reports/experiments/2026-11-30b
C=reports/experiments/2026-11-28/distortion/collect.py
# 1. the captures alone under the default (at c2be2c7); the statue kept with its checkpoints for the probes below
/usr/bin/time -v python scripts/train.py $D/garden --out $W/garden > $W/garden.log 2>&1
/usr/bin/time -v python scripts/train.py $D/statue --out $W/statue --keep-checkpoints > $W/statue.log 2>&1
/usr/bin/time -v python scripts/train.py $D/horns --out $W/horns > $W/horns.log 2>&1
/usr/bin/time -v python scripts/train.py $D/lego_200 --out $W/lego_200 > $W/lego_200.log 2>&1
python $C reports/captures/cpu_2026-11-30_s28_alone.json "python scripts/train.py ../shared/data/CAPTURE --out RUN" \
  "the default command at c2be2c7 (grey degree 1), each alone on the 2 cores (the statue with --keep-checkpoints; horns had a probe of a minute or two beside it, so its wall time is an upper bound)" \
  garden=$W/garden statue=$W/statue horns=$W/horns lego_200=$W/lego_200
# 2. garden with near_grad 1 under grey degree 1
/usr/bin/time -v python scripts/train.py $D/garden --out $W/garden_ng1 --set near_grad=1 > $W/garden_ng1.log 2>&1
python $C reports/captures/cpu_2026-11-30_garden_near_grad1_grey.json "python scripts/train.py ../shared/data/garden --out RUN --set near_grad=1" \
  "at c2be2c7 (grey degree 1 the default), alone on the 2 cores; not the default" garden=$W/garden_ng1
python $E/garden_ng/sheet.py $W/garden_views.png 16,64,112 $W/garden $W/garden_ng1   # the PNG in garden_ng/ is view 16's crop
# 3. render-time pruning on the statue's fit
python $E/render_prune/prune.py $W/statue 1:4:1e-4 1:2:1e-4 3:4:1e-4 10:4:1e-4 30:4:1e-4 10:2:1e-3 3:2:1e-3
# 4. the statue's column: background refits (the trial rows from a copy of the package with statue_column/fill_trial.diff,
#    FILL_CENTRE=median FILL_ALONG=1), the fill's boundary, a ray through the column
for s in "" keep_seen_gap=3 keep_seen=false hull_fill_vertical=1 hull_dilation=0.08 hull_color_fill=true steps_bg=1; do
  python -m mi_voldis.bench.strategies $W/statue guided $W/statue_bg/${s:-base} --refit ${s:+--set $s}
done
python -m mi_voldis.bench.strategies $W/statue clear $W/statue_bg/clear --refit
python $E/statue_column/compare.py $W/view8.png 8 $W/statue_bg/base $W/statue_bg/clear
python $E/statue_column/fill_boundary.py $W/statue
python reports/experiments/2026-11-29c/coverage/ray_regions.py $W/statue 8 255,180 300,200 200,180 330,180
# 5. the fill's up at the hull's median: the axis weights on the contracted family scenes and the statue, then the
#    contracted family scenes' backgrounds refitted with the fix (FITS: the committed family fits, with checkpoints)
python $E/fill_up/fill_up.py $W/statue $FITS/runs/family{17,01,03,05,07,09,11,13,15,19,06}_0
sh reports/experiments/2026-11-28/bg_trials/refit.sh $FITS $W/fillfix "09 17 01 03 05 07 11 13 15 19"
python reports/experiments/2026-11-29g/gloss_keep_seen/screen.py $W/fillfix > $E/fill_up/refits_screen.txt
# 6. garden's vase with the box masks under today's default (reports/garden_removal.md), at c248395
python scripts/train.py $D/garden --out $W/gbox/run --keep-checkpoints
python scripts/make_masks.py $D/garden --out $W/gbox/masks --run $W/gbox/run --box 0.45,-0.1,-1.05,1.77,0.7,-0.15
python -c "from mi_voldis.bench.masks import masked_copy; masked_copy('$D/garden', '$W/gbox/masks', '$W/gbox/data')"
python -m mi_voldis.bench.strategies $W/gbox/run guided $W/gbox/out $W/gbox/data
cp $W/gbox/out/metrics.json $E/garden_box/metrics.json
python $E/garden_box/fill_axis.py $W/gbox/run $W/gbox/data > $E/garden_box/fill_axis.txt
