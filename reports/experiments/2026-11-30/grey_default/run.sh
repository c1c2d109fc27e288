#!/bin/bash
# The commands behind reports/notes.md, "2026-11-30 (twenty-seventh session)". Run from the repository root at
# adbeebf (VIEW_STEP_COST 1.1, the default colour still degree 0 'auto'); W: a scratch folder. Two bench processes
# ran side by side (and lego_200's fit beside them for its first half hour), so no wall time is a timing; the plan's
# step counts come from the reference speed, so the results do not depend on the load.
set -e
D=${DATA:-../shared/data}
W=${W:-runs}
E=reports/experiments/2026-11-30/grey_default
# 1. the removal family under grey degree 1, tuning half first, in two processes
for half in A B; do
  if [ $half = A ]; then T=family00,family02,family04,family06,family08; C=family10,family12,family14,family16,family18
  else T=family01,family03,family05,family07,family09; C=family11,family13,family15,family17,family19; fi
  ( python scripts/bench.py --family --scenes $T --work $W/tune_$half --report $W/tune_$half/report \
      --set sh_degree=1 --set 'sh_color="grey"'
    python scripts/bench.py --family --scenes $C --work $W/check_$half --report $W/check_$half/report \
      --set sh_degree=1 --set 'sh_color="grey"' ) &
done
# 2. lego_200 at VIEW_STEP_COST 1.1 (the other captures: reports/captures/cpu_2026-11-30_grey_view_cost_1_1.json)
/usr/bin/time -v python scripts/train.py $D/lego_200 --out $W/lego_200 --set sh_degree=1 --set sh_color=grey \
  > $W/lego_200.log 2>&1
wait
python reports/experiments/2026-11-28/distortion/collect.py reports/captures/cpu_2026-11-30_lego_grey_view_cost_1_1.json \
  "python scripts/train.py ../shared/data/lego_200 --out RUN --set sh_degree=1 --set sh_color=grey" \
  "VIEW_STEP_COST 1.1; beside two family fits (three processes on 2 cores), so the wall time is no timing" \
  lego_200=$W/lego_200
# the family against the committed degree-0 rows (reports/family.json, before step 3 rewrites it)
python reports/experiments/2026-11-29g/gloss_keep_seen/screen.py $W/tune_A $W/tune_B $W/check_A $W/check_B \
  > $E/screen.txt
# 3. at the commit that made grey degree 1 the default: the bench's own report, every fit reused
python reports/experiments/2026-11-29h/grey_charged/merge_work.py $W/family_all $W/tune_A $W/tune_B $W/check_A $W/check_B
python scripts/bench.py --family --work $W/family_all
# 4. at 3eab5d0, alone on the machine: the statue under the new default, for its wall time
/usr/bin/time -v python scripts/train.py $D/statue --out $W/statue_alone > $W/statue_alone.log 2>&1
python reports/experiments/2026-11-28/distortion/collect.py reports/captures/cpu_2026-11-30_statue_alone.json \
  "python scripts/train.py ../shared/data/statue --out RUN" \
  "the default command at 3eab5d0 (grey degree 1), alone on the 2 cores" statue=$W/statue_alone
# 5. at 70bbacb, alone on the machine: fern under the new default, for its wall time
/usr/bin/time -v python scripts/train.py $D/fern --out $W/fern_alone > $W/fern_alone.log 2>&1
python reports/experiments/2026-11-28/distortion/collect.py reports/captures/cpu_2026-11-30_fern_alone.json \
  "python scripts/train.py ../shared/data/fern --out RUN" \
  "the default command at 70bbacb (grey degree 1), alone on the 2 cores" fern=$W/fern_alone
