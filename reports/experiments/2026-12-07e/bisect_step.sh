#!/bin/bash
# git bisect run helper: fit family15 (SPIn-NeRF layout) at the checked-out commit; good if the fit's bg_psnr_mask > 20.9
export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
h=$(git rev-parse --short HEAD)
out=/work/runs/s64/bis/run_$h
# a run folder of this commit already there is not ours to replace: skip the commit (as run, the step removed its
# own earlier folders instead)
[ -e "$out" ] || [ -e "$out.partial" ] && { echo "$out exists" >&2; exit 125; }
PYTHONPATH=$PWD timeout 1200 /work/main/.venv/bin/python scripts/train.py /work/runs/s63/spin/data/family15_spinnerf --out $out --quiet > /work/runs/s64/bis/log_$h.txt 2>&1 || exit 125
v=$(python3 -c "import json;print(json.load(open('$out/metrics.json'))['held_out']['bg_psnr_mask'])") || exit 125
echo "$h $v" >> /work/runs/s64/bis/results.txt
python3 -c "import sys;sys.exit(0 if $v > 20.9 else 1)"
