#!/bin/bash
# the statue fitted with the default command, then with free_space=true, one after the other, alone; the runs,
# logs and times.txt in OUT (default /work/runs/s66/statue):  time_statue.sh [OUT]
OUT=${1:-/work/runs/s66/statue}
mkdir -p $OUT
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
cd /work/main
for k in default free; do
  extra=""; [ $k = free ] && extra="--set free_space=true"
  s=$(date +%s.%N)
  .venv/bin/python scripts/train.py /work/shared/data/statue --out $OUT/$k $extra > $OUT/$k.log 2>&1
  e=$(date +%s.%N)
  echo "$k wall $(echo "$e - $s" | bc) s" >> $OUT/times.txt
done
