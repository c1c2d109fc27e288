#!/bin/bash
# the statue's first 240 s of fitting, default then free_space=true, alone: per-stage step times from log.json
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
cd /work/main
for k in default free; do
  extra=""; [ $k = free ] && extra="--set free_space=true"
  rm -rf /work/runs/s67/st_$k
  timeout 240 .venv/bin/python scripts/train.py /work/shared/data/statue --out /work/runs/s67/st_$k $extra > /work/runs/s67/st_$k.log 2>&1
done
echo done > /work/runs/s67/statue_steps.done
