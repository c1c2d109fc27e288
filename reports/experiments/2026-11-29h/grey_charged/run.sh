#!/bin/bash
# The commands behind reports/notes.md, "2026-11-29 (twenty-sixth session)". Run from the repository root at
# 6d8f615 (the package as the twenty-fifth session left it: VIEW_STEP_COST 1.3); W: a scratch folder.
# The captures ran two at a time beside the family screen, so their wall times are not timings; the plan's step
# counts come from the reference speed, so the results do not depend on the load.
set -e
D=${DATA:-../shared/data}
W=${W:-runs}
E=reports/experiments/2026-11-29h/grey_charged
T="/usr/bin/time -v"
# 1. the captures with grey degree 1 on the view lattice, charged for it (the session's runs made the same fits
#    with these two settings as the defaults; bench.run.finished confirms the resolved settings are equal)
for c in garden fern statue horns lego_200; do
  $T python scripts/train.py $D/$c --out $W/$c --set sh_degree=1 --set sh_color=grey > $W/$c.log 2>&1
done
python reports/experiments/2026-11-28/distortion/collect.py reports/captures/cpu_2026-11-29_grey_charged.json \
  "python scripts/train.py ../shared/data/CAPTURE --out RUN --set sh_degree=1 --set sh_color=grey" \
  "grey degree 1 on a 64^3 view lattice from half the steps, the plan charging VIEW_STEP_COST 1.3 after the onset (kernel_scale 1.15); two fits at a time beside the family screen, so wall times are not timings" \
  garden=$W/garden fern=$W/fern statue=$W/statue horns=$W/horns lego_200=$W/lego_200
python $E/plans.py reports/captures/cpu_2026-11-27_step_auto.json reports/captures/cpu_2026-11-29_grey_charged.json \
  > $E/plans.txt
# which step each capture's plan takes at other charges for the view lattice, rebuilt from the recorded plans
python $E/step_choice.py $W/fern $W/horns $W/statue $W/garden > $E/step_choice.txt
# 2. the removal family's tuning half, the six scenes the last session did not fit (three per process)
python scripts/bench.py --family --scenes family03,family05,family08 --work $W/tune_E --report $W/tune_E/report \
  --set sh_degree=1 --set 'sh_color="grey"'
python scripts/bench.py --family --scenes family04,family07,family09 --work $W/tune_F --report $W/tune_F/report \
  --set sh_degree=1 --set 'sh_color="grey"'
# the whole family (last session's four folders and these two) against the committed degree-0 rows
python reports/experiments/2026-11-29g/gloss_keep_seen/screen.py $W/check_A $W/check_B $W/tune_C $W/tune_D \
  $W/tune_E $W/tune_F > $E/screen.txt
# and as the bench's own trial report (family.md, contact sheets), every fit and row reused
python $E/merge_work.py $W/family_all $W/check_A $W/check_B $W/tune_C $W/tune_D $W/tune_E $W/tune_F
python scripts/bench.py --family --work $W/family_all --report $E/report --set sh_degree=1 --set 'sh_color="grey"'
# 3. at 75d82fc (VIEW_STEP_COST 1.1): the captures again, to confirm the rebuilt plans (two at a time here)
for c in fern statue horns garden; do
  $T python scripts/train.py $D/$c --out $W/v11_$c --set sh_degree=1 --set sh_color=grey > $W/v11_$c.log 2>&1 &
done
wait
python reports/experiments/2026-11-28/distortion/collect.py reports/captures/cpu_2026-11-30_grey_view_cost_1_1.json \
  "python scripts/train.py ../shared/data/CAPTURE --out RUN --set sh_degree=1 --set sh_color=grey" \
  "VIEW_STEP_COST 1.1" fern=$W/v11_fern statue=$W/v11_statue horns=$W/v11_horns garden=$W/v11_garden
