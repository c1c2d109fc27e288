set -e
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
cd /work/main
PY=/work/main/.venv/bin/python
R=/work/runs/s63/refl
$PY scripts/make_masks.py /work/shared/data/garden --out $R/effects --effects --run /work/runs/s63/garden_fit --quiet \
  --from-views frame_00184=$R/sel/frame_00184.png frame_00176=$R/sel/frame_00176.png frame_00128=$R/sel/frame_00128.png > $R/effects.log 2>&1
mkdir -p $R/data
for f in PROVENANCE.txt images sparse_pc.ply transforms.json; do ln -s /work/shared/data/garden/$f $R/data/$f; done
ln -s /work/runs/s63/garden_box/masks $R/data/masks
ln -s $R/effects $R/data/effects
/usr/bin/time -v $PY -m mi_voldis.bench.strategies /work/runs/s63/garden_fit guided $R/out $R/data > $R/strategies.log 2>&1
echo done
