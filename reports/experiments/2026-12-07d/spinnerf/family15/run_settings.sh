set -e
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
cd /work/main
PY=/work/main/.venv/bin/python
R=/work/runs/s63/f15
for s in hull_occluders=false object_front=false keep_seen=false hull_color_fill=true prior_inpainter=telea; do
  $PY -m mi_voldis.bench.strategies $R/run guided $R/t_${s%%=*} --set $s > $R/t_${s%%=*}.log 2>&1 || echo "fail $s"
done
echo done
