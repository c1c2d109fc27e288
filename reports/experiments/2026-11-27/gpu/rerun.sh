#!/usr/bin/env bash
# The second device call of 2026-11-27 (#42): the suite on cuda_ad_rgb (the first call's run lacked the scenes'
# textures) beside the default command on fern and garden with the sample bound (a fit refines no further once
# more than 1% of its rays reach max_samples), all at once on one GPU: wall times are upper bounds.
#
#   reports/experiments/2026-11-27/gpu/rerun.sh OUT CAPTURES     # from the checkout; carry .gpu and CAPTURES
#
# OUT gets tests.log, smi.csv (GPU memory every 5 s), summary.txt and
# one NAME.tgz per fit (its run folder without the grids), each packed as soon as that fit ends.
set -u
OUT=$1
CAPTURES=$2
LIMIT=${GPU_RUN_LIMIT:-330}  # seconds any one job may take: what is left of the session's device time
BUNDLE=${GPU_BUNDLE-.gpu/site312.tar.xz}  # empty: Mitsuba from the Python in use (a dry run on the CPU)
RUNS=$(mktemp -d)
mkdir -p "$OUT"
if [ -n "$BUNDLE" ]; then
    python3 -c "import sys, tarfile; tarfile.open(sys.argv[1]).extractall('/tmp/site')" "$BUNDLE" || exit 1
fi
export PYTHONPATH=${BUNDLE:+/tmp/site:}$PWD MI_VOLDIS_VARIANT=${MI_VOLDIS_VARIANT:-cuda_ad_rgb} PYTHONUNBUFFERED=1
export MI_VOLDIS_CAPTURES=$PWD/$CAPTURES
{ nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv; nproc; } > "$OUT/summary.txt" 2>&1
nvidia-smi --query-gpu=timestamp,memory.used,utilization.gpu --format=csv -l 5 > "$OUT/smi.csv" 2>&1 &
SMI=$!

fit() {  # fit NAME CAPTURE [--set ...]: the default command, then its run folder packed without the grids
    local name=$1 capture=$2
    shift 2
    local t0=$SECONDS
    timeout "$LIMIT" python3 scripts/train.py "$CAPTURES/$capture" --out "$RUNS/$name" \
        --variant "$MI_VOLDIS_VARIANT" "$@" > "$RUNS/$name.log" 2>&1
    local rc=$?
    echo "$name: exit $rc in $((SECONDS - t0)) s: train.py $capture $*" >> "$OUT/summary.txt"
    tar -C "$RUNS" -czf "$OUT/$name.tgz" --exclude='*.npz' "$name.log" "$name"
}
fit fern fern &
fit garden garden &
t0=$SECONDS
timeout "$LIMIT" python3 -m pytest -q -rfEs -p no:cacheprovider -n 8 tests > "$OUT/tests.log" 2>&1
echo "tests: exit $? in $((SECONDS - t0)) s" >> "$OUT/summary.txt"
wait $(jobs -p | grep -v "^$SMI$")
kill "$SMI"
cat "$OUT/summary.txt"
tail -n 3 "$OUT/tests.log"
for f in "$RUNS"/*.log; do echo "== $f"; tail -n 4 "$f"; done
