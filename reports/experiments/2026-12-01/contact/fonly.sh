#!/bin/sh
# the fringe-only variant (fringe_unseen=false) refitted from the default fits: fonly.sh FITS "NN ..."
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
cd /tmp/exp4
for s in $2; do
  while [ ! -f $1/runs/family${s}_0/metrics.json ]; do sleep 20; done
  sh refit.sh $1 /work/runs/s30/fonly_$(basename $1) "$s" --set fringe_unseen=false
  echo "family$s done $(date +%H:%M)"
done
