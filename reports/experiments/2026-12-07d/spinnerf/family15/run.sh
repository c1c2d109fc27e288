set -e
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
cd /work/main
PY=/work/main/.venv/bin/python
D=/work/runs/s63/spin/data/family15_spinnerf
R=/work/runs/s63/f15
$PY scripts/train.py $D --out $R/run --keep-checkpoints --quiet > $R/train.log 2>&1
$PY -m mi_voldis.bench.strategies $R/run guided $R/default --refit > $R/default.log 2>&1
$PY -m mi_voldis.bench.strategies $R/run guided $R/no_fringe --set fringe_contrast=0 > $R/no_fringe.log 2>&1
$PY -m mi_voldis.bench.strategies $R/run guided $R/no_fringe_unseen --set fringe_unseen=false > $R/no_fringe_unseen.log 2>&1
$PY -m mi_voldis.bench.strategies $R/run guided $R/no_shadow --set shadow_contrast=0 > $R/no_shadow.log 2>&1
echo done
