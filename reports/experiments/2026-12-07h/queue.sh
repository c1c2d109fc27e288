#!/bin/bash
# one worker (bench/queue.sh under /work/runs/s67): KIND (def: the default; told: --set free_space=true) fits the scenes in SCENES order, one bench invocation each, in its own
# clone at COMMIT; work and report per scene under /work/runs/s67/bench/KIND/familyNN
KIND=$1; COMMIT=$2; shift 2
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
C=/tmp/c67_$KIND
[ -d $C ] || git clone -q /work/main $C
cd $C && git checkout -q $COMMIT
extra=""; [ $KIND != def ] && extra="--set free_space=true"
for s in "$@"; do
  W=/work/runs/s67/bench/$KIND/$s
  mkdir -p $W
  echo "$(date +%T) start $s" >> /work/runs/s67/bench/$KIND.log
  PYTHONPATH=$C /work/main/.venv/bin/python scripts/bench.py --family --scenes $s $extra --work $W/work --report $W/rep > $W/bench.log 2>&1
  echo "$(date +%T) end $s rc=$?" >> /work/runs/s67/bench/$KIND.log
done
