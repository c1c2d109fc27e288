#!/bin/bash
# usage: chain.sh SCENE...  fits each family scene as a 360-degree capture without a stated box (space=contract),
# the shell at Mip-NeRF 360's 1 and at 'auto' (0.25), the full field only (steps_bg=1)
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
cd /work/main
for s in "$@"; do
  for b in 1 auto; do
    sets=(--set space=contract --set steps_bg=1)
    [ $b = 1 ] && sets+=(--set contract_shell=1)
    .venv/bin/python scripts/train.py /work/runs/s42/data/$s --out /work/runs/s42/o360/${s}_b$b --quiet "${sets[@]}" \
      > /work/runs/s42/o360/${s}_b$b.log 2>&1
  done
done
