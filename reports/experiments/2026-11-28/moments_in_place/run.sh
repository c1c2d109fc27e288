#!/bin/bash
# The commands behind reports/notes.md, 2026-11-28 (thirteenth session). Run from the repository root, each
# alone on the machine. The in-place rows (statue_mem_views, fern_ip, garden_sh1_v) ran with
# `git apply reports/experiments/2026-11-28/moments_in_place/adam_in_place.diff` (BYTES_PER_VERTEX 272); the four
# *_v rows of cpu_2026-11-28_bytes240.json with the diff applied and BYTES_PER_VERTEX = 240 in
# mi_voldis/fit/schedule.py.
set -e
D=${DATA:-../shared/data}
python reports/experiments/2026-11-28/moments_in_place/adam_peak.py 45e6 4 2 > reports/experiments/2026-11-28/moments_in_place/adam_peak.txt
python reports/experiments/2026-11-28/moments_in_place/adam_peak.py 29.5e6 16 2 >> reports/experiments/2026-11-28/moments_in_place/adam_peak.txt
python reports/experiments/2026-11-28/moments_in_place/bare_kernel.py oop flat packet \
  > reports/experiments/2026-11-28/moments_in_place/bare_kernel.txt
python reports/experiments/2026-11-27/memory/phase_peaks.py -- $D/statue --out runs/statue_mem_views \
  --set 'resolution_schedule=[[0,64],[200,368]]' --set steps_full=450
/usr/bin/time -v python scripts/train.py $D/fern --out runs/fern_ip > runs/fern_ip.log 2>&1
/usr/bin/time -v python scripts/train.py $D/garden --out runs/garden_sh1_v --set sh_degree=1 --set near_grad=1 \
  --set contract_radius=0.5 > runs/garden_sh1_v.log 2>&1
for c in statue garden horns fern; do  # BYTES_PER_VERTEX = 240
  /usr/bin/time -v python scripts/train.py $D/$c --out runs/${c}_v > runs/${c}_v.log 2>&1
done
python reports/experiments/2026-11-28/distortion/collect.py reports/captures/cpu_2026-11-28_bytes240.json \
  "python scripts/train.py ../shared/data/CAPTURE --out RUN (BYTES_PER_VERTEX 240)" "each alone" \
  statue=runs/statue_v garden=runs/garden_v horns=runs/horns_v fern=runs/fern_v
python reports/experiments/2026-11-28/distortion/collect.py reports/captures/cpu_2026-11-28_moments_in_place.json \
  "python scripts/train.py ... (adam_in_place.diff applied)" "the same plans as the default rows" \
  fern_moments_in_place=runs/fern_ip garden_sh1_moments_in_place=runs/garden_sh1_v
python reports/experiments/2026-11-28/ray_bank/bank_memory.py $D/fern $D/statue $D/horns $D/garden $D/lego_200 \
  > reports/experiments/2026-11-28/ray_bank/bank_memory.txt
# side by side, back to back: the package, then the diff applied (in a worktree)
/usr/bin/time -v python scripts/train.py $D/fern --out runs/fern_pkg2 > runs/fern_pkg2.log 2>&1
git apply reports/experiments/2026-11-28/moments_in_place/adam_in_place.diff
/usr/bin/time -v python scripts/train.py $D/fern --out runs/fern_ip2 > runs/fern_ip2.log 2>&1
git apply -R reports/experiments/2026-11-28/moments_in_place/adam_in_place.diff
python reports/experiments/2026-11-28/distortion/collect.py reports/captures/cpu_2026-11-28_moments_side_by_side.json \
  "python scripts/train.py ../shared/data/fern --out RUN" "back to back" fern_package=runs/fern_pkg2 fern_in_place=runs/fern_ip2
