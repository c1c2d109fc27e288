set -e
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
cd /tmp/c63t
R=/work/runs/s63/refl
TRIAL_EFFECT_GREY=1 PYTHONPATH=/tmp/c63t /usr/bin/time -v /work/main/.venv/bin/python -m mi_voldis.bench.strategies /work/runs/s63/garden_fit guided $R/out_grey $R/data > $R/trial.log 2>&1
echo done
