#!/bin/sh
# How the hull_color_fill figures of reports/notes.md ("The hole's colour from outside the hull", 2026-11-28)
# were made. W: the work folder of `python scripts/bench.py --family` (default fits; the rows it wrote are the
# "off" rows); T: that of the earlier twice-the-TV trial (reports/experiments/2026-11-28/family_tv2/).
set -eu
W=${W:-/tmp/family}; T=${T:-/tmp/family_tv2}; O=${O:-/tmp/color_fill}
PY=${PYTHON:-.venv/bin/python}
E=reports/experiments/2026-11-28/color_fill
$PY scripts/bench.py --family --work $W --report $O/report   # the default fits and their `guided` rows
for k in 00 01 02 03 04 05 06 07 08 17; do   # rows_default_fits_on.txt
  $PY $E/rows.py $O/on $W/runs/family${k}_0 --set hull_color_fill=true
done
for k in 06 02 01 04; do   # rows_default_fits_on_hole_carve.txt
  $PY $E/rows.py $O/hc_on $W/runs/family${k}_0 --set hull_color_fill=true --set hole_carve=true
done
for k in 04 16 05 11 13; do   # rows_tv2_fits_on.txt (rows_tv2_fits_off.txt: the trial's own `guided` rows)
  $PY $E/rows.py $O/tv2_on $T/runs/family${k}_0 --set hull_color_fill=true
done
# rows_tv2_fits_whole_hull.txt: the first version, which gave the kept vertices the fill's colour as well
# (every tv2 fit, 00-16); compare_*.txt: python $E/compare.py OFF.txt ON.txt
$PY $E/ghost_views.py $W/runs/family06_0 $E/family06_start.png 0,1,8,9 --set steps_bg=0
$PY $E/ghost_views.py $W/runs/family06_0 $E/family06_default.png 0,1,8,9
$PY $E/ghost_views.py $W/runs/family06_0 $E/family06_hull_color_fill.png 0,1,8,9 --set hull_color_fill=true
$PY $E/sphere.py   # sphere.txt
for s in "" "--set hole_carve=true" "--set hull_color_fill=true"; do   # front_weight.txt
  $PY $E/front_weight.py $W/runs/family06_0 $s
done
