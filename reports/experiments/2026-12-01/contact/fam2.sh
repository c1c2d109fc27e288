#!/bin/sh
# fit family scenes (default command, checkpoints kept) and refit the background with the fringe code:
#   fam2.sh WORK "NN NN ..."   (fits from /tmp/exp1 = the committed code; refits from /tmp/exp2)
W=$1
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
mkdir -p $W/runs $W/logs
for s in $2; do
  if [ ! -f $W/runs/family${s}_0/metrics.json ]; then
    cd /tmp/exp1 && .venv/bin/python scripts/train.py /work/runs/s30/data/family$s --out $W/runs/family${s}_0 --quiet --keep-checkpoints > $W/logs/family${s}_0.log 2>&1 || echo "family$s fit failed"
  fi
  cd /tmp/exp2 && sh refit.sh $W /work/runs/s30/fringe_$(basename $W) "$s"
  echo "family$s done $(date +%H:%M)"
done
