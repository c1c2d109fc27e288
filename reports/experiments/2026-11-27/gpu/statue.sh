#!/usr/bin/env bash
# The third device call of 2026-11-27 (#42): the default command on the statue alone on one GPU (its row was never
# finished there), inside what was left of the session's device time.
#
#   reports/experiments/2026-11-27/gpu/statue.sh OUT CAPTURES     # from the checkout; carry .gpu and CAPTURES
set -u
OUT=$1
CAPTURES=$2
LIMIT=${GPU_RUN_LIMIT:-260}
RUNS=$(mktemp -d)
mkdir -p "$OUT"
python3 -c "import sys, tarfile; tarfile.open(sys.argv[1]).extractall('/tmp/site')" .gpu/site312.tar.xz || exit 1
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1
nvidia-smi --query-gpu=timestamp,memory.used,utilization.gpu --format=csv -l 5 > "$OUT/smi.csv" 2>&1 &
SMI=$!
t0=$SECONDS
timeout "$LIMIT" python3 scripts/train.py "$CAPTURES/statue" --out "$RUNS/statue" --variant cuda_ad_rgb \
    > "$RUNS/statue.log" 2>&1
echo "statue: exit $? in $((SECONDS - t0)) s" | tee "$OUT/summary.txt"
kill "$SMI"
tar -C "$RUNS" -czf "$OUT/statue.tgz" --exclude='*.npz' statue.log statue
tail -n 30 "$RUNS/statue.log"
