#!/usr/bin/env bash
# A device call of #42's GPU rows: the suite on cuda_ad_rgb beside default commands, all at once on one GPU. The
# default plan is costed in samples, not seconds, so running beside each other changes wall times (upper bounds),
# not the fits. The first call of 2026-11-27 as it ran (rerun.sh and statue.sh: the second and third):
#
#   reports/experiments/2026-11-27/gpu/run.sh OUT CAPTURES     # from the checkout; carry .gpu and CAPTURES
#
# GPU_RUN_FITS: "NAME:CAPTURE[:SETTING,...] ..." (default: fern, horns, garden and two fern variants);
# GPU_RUN_TESTS: pytest's arguments (empty: no suite); GPU_RUN_LIMIT: seconds any one job may take.
# OUT (a new or empty folder) gets tests.log, smi.csv (GPU memory every 5 s), summary.txt and one NAME.tgz per
# fit (its run folder without the grids), each packed as soon as that fit ends: at most 8 files come back.
set -u
OUT=$1
CAPTURES=$2
FITS=${GPU_RUN_FITS-"fern:fern fern_b131k:fern:batch_rays=131072 fern_r512:fern:max_resolution=512 horns:horns garden:garden"}
TESTS=${GPU_RUN_TESTS-"-n 6 tests"}
LIMIT=${GPU_RUN_LIMIT:-510}  # the call's own limit is 600
if [ -e "$OUT" ] && [ -n "$(ls -A "$OUT")" ]; then
    echo "run.sh: $OUT is not empty: give a new or empty folder (nothing there is replaced)" >&2
    exit 1
fi
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

fit() {  # fit NAME CAPTURE [SETTING,...]: the default command, then its run folder packed without the grids
    local name=$1 capture=$2 sets=() s
    IFS=, read -r -a list <<< "${3:-}"
    for s in "${list[@]}"; do sets+=(--set "$s"); done
    local t0=$SECONDS
    timeout "$LIMIT" python3 scripts/train.py "$CAPTURES/$capture" --out "$RUNS/$name" \
        --variant "$MI_VOLDIS_VARIANT" "${sets[@]}" > "$RUNS/$name.log" 2>&1
    local rc=$?
    echo "$name: exit $rc in $((SECONDS - t0)) s: train.py $capture ${sets[*]}" >> "$OUT/summary.txt"
    tar -C "$RUNS" -czf "$OUT/$name.tgz" --exclude='*.npz' "$name.log" "$name"
}
pids=()
for spec in $FITS; do
    IFS=: read -r name capture sets <<< "$spec"
    fit "$name" "$capture" "$sets" &
    pids+=("$!")
done
if [ -n "$TESTS" ]; then
    t0=$SECONDS
    read -r -a args <<< "$TESTS"
    timeout "$LIMIT" python3 -m pytest -q -rfEs -p no:cacheprovider "${args[@]}" > "$OUT/tests.log" 2>&1
    echo "tests: exit $? in $((SECONDS - t0)) s" >> "$OUT/summary.txt"
fi
for pid in "${pids[@]}"; do wait "$pid"; done
kill "$SMI"
cat "$OUT/summary.txt"
[ -z "$TESTS" ] || tail -n 3 "$OUT/tests.log"
for f in "$RUNS"/*.log; do echo "== $f"; tail -n 4 "$f"; done
