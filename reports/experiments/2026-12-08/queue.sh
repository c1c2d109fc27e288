#!/bin/bash
# one worker: fits KIND:SCENE entries in order (KIND def = default, told = --set free_space=true), one bench
# invocation each, from a clone of main at COMMIT; work and report under /work/runs/s68/bench/KIND/SCENE
NAME=$1; COMMIT=$2; shift 2
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
C=/tmp/c68_$NAME
[ -d $C ] || git clone -q /work/main $C
cd $C && git checkout -q $COMMIT
for e in "$@"; do
  k=${e%%:*}; s=${e#*:}
  extra=""; [ $k != def ] && extra="--set free_space=true"
  W=/work/runs/s68/bench/$k/$s
  mkdir -p $W/work/data
  src=$(ls -d /work/runs/s67/bench/told/$s/work/data/$s 2>/dev/null | head -1)
  [ -n "$src" ] && [ ! -e $W/work/data/$s ] && cp -r $src $W/work/data/
  echo "$(date +%T) start $k $s" >> /work/runs/s68/bench/$NAME.log
  PYTHONPATH=$C /work/main/.venv/bin/python scripts/bench.py --family --scenes $s $extra --work $W/work --report $W/rep > $W/bench.log 2>&1
  echo "$(date +%T) end $k $s rc=$?" >> /work/runs/s68/bench/$NAME.log
done
