#!/usr/bin/env bash
# The test suite and the benchmark's CUDA rows on a GPU machine, in one command that prints each
# command before it runs it and, at the end, what ran and how it ended.
#
#   scripts/gpu_check.sh [OUT]     # OUT: logs and reports (default: $OUT, else out/gpu_check); a new or empty
#                                  # folder, or one an earlier gpu_check wrote
#
# Steps (each one's output also in OUT/<step>.log; the exit status is the number of failed steps):
#   env      Python, Mitsuba / Dr.Jit versions, the GPU (nvidia-smi), OpenCV with or without contrib
#   tests    MI_VOLDIS_VARIANT=cuda_ad_rgb python -m pytest -q -rfEs tests   (pytest's header names the variant)
#   profile  python scripts/bench.py --step-profile --batch $GPU_CHECK_BATCHES --variant cuda_ad_rgb
#            (OUT/step_profile.json: each kernel's time, and their share of the step at each batch)
#   captures python scripts/train.py CAPTURES/NAME --out OUT/captures/NAME --variant cuda_ad_rgb, the default
#            command, for each NAME of GPU_CHECK_CAPTURES, all at once (OUT/captures_NAME.log): the default
#            plan is costed in samples, not seconds, so running beside each other changes their wall times
#            (then upper bounds), not their fits
#   quick    python scripts/bench.py --quick --variant cuda_ad_rgb --report OUT/report  (runs and datasets
#            in $TMPDIR, not in OUT; the checkout's reports/ stays as it is)
#
# On the GPU machine the device tool lends (Python 3.12, no package registry), a bundle made here by
# ../shared/tools/gpu_bundle.sh (.gpu/site312.tar.xz, carried with the checkout: carry [".gpu"]) is
# unpacked to $TMPDIR/site and put on PYTHONPATH first. Knobs: PYTHON (default .venv/bin/python where
# present, else python3), GPU_BUNDLE (default .gpu/site312.tar.xz), GPU_CHECK_VARIANT (default
# cuda_ad_rgb), GPU_CHECK_STEPS (default "env tests profile quick"), GPU_CHECK_TESTS (pytest's
# arguments, default "tests"), GPU_CHECK_BATCHES (rays per profiled step, default "16384,65536,262144"),
# GPU_CHECK_CAPTURES (default "fern statue garden"), CAPTURES (their folder: default $MI_VOLDIS_CAPTURES,
# else ../shared/data), GPU_CHECK_TIMEOUT (seconds any one step may run: a device call has a limit of
# its own, and what a step wrote before it was stopped is kept), GPU_CHECK_ARCHIVE (a .tgz path: OUT
# without the fields' grids and checkpoints, packed again after every step, so that one file carries it
# all back where only a few files may return, e.g. $OUT/gpu_check.tgz with OUT a folder in $TMPDIR).
#
# The device tool carries at most 64 MiB: the bundle (21 MiB slimmed) and the captures copied into an
# ignored folder leave little room for the checkout's report PNGs; move aside only reports/*.png (the
# scenes' textures in mi_voldis/scenes/ are needed by the suite), and put them back afterwards.
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
DEST=${1:-${OUT:-out/gpu_check}}
# OUT holds what gpu_check wrote (marked by OUT/.gpu_check, which lists the archives it wrote) or nothing: a
# folder or an archive it did not write is refused, never replaced
if [ -e "$DEST" ] && [ -n "$(ls -A "$DEST")" ] && [ ! -f "$DEST/.gpu_check" ]; then
    echo "gpu_check: $DEST holds files gpu_check did not write: give a new or empty folder" >&2
    exit 1
fi
if [ -n "${GPU_CHECK_ARCHIVE:-}" ] && [ -e "$GPU_CHECK_ARCHIVE" ] &&
    ! grep -qxF "$GPU_CHECK_ARCHIVE" "$DEST/.gpu_check" 2>/dev/null; then
    echo "gpu_check: $GPU_CHECK_ARCHIVE is already there and gpu_check did not write it into $DEST: name another" >&2
    exit 1
fi
mkdir -p "$DEST"
DEST=$(cd "$DEST" && pwd)
touch "$DEST/.gpu_check"
if [ -n "${GPU_CHECK_ARCHIVE:-}" ] && ! grep -qxF "$GPU_CHECK_ARCHIVE" "$DEST/.gpu_check"; then
    echo "$GPU_CHECK_ARCHIVE" >> "$DEST/.gpu_check"
fi
TMP=${TMPDIR:-/tmp}
VARIANT=${GPU_CHECK_VARIANT:-cuda_ad_rgb}
STEPS=${GPU_CHECK_STEPS:-env tests profile quick}
read -r -a TESTS <<< "${GPU_CHECK_TESTS:-tests}"
BATCHES=${GPU_CHECK_BATCHES:-16384,65536,262144}
read -r -a CAPTURE_NAMES <<< "${GPU_CHECK_CAPTURES:-fern statue garden}"
CAPTURES=${CAPTURES:-${MI_VOLDIS_CAPTURES:-../shared/data}}
if [ -z "${PYTHON:-}" ]; then
    if [ -x .venv/bin/python ]; then PYTHON=.venv/bin/python; else PYTHON=python3; fi
fi
BUNDLE=${GPU_BUNDLE:-.gpu/site312.tar.xz}

say() { printf '%s\n' "$*" | tee -a "$DEST/commands.txt"; }
: > "$DEST/commands.txt"
if [ -f "$BUNDLE" ]; then
    say "+ unpack $BUNDLE into $TMP/site (PYTHONPATH)"
    "$PYTHON" -c "import sys, tarfile; tarfile.open(sys.argv[1]).extractall(sys.argv[2])" "$BUNDLE" "$TMP/site" || exit 1
    export PYTHONPATH="$TMP/site:$ROOT${PYTHONPATH:+:$PYTHONPATH}"
else
    export PYTHONPATH="$ROOT${PYTHONPATH:+:$PYTHONPATH}"
fi
export MI_VOLDIS_VARIANT=$VARIANT PYTHONUNBUFFERED=1
# the suite's capture tests read the same folder (skipped, with the reason, where it is missing)
[ -d "$CAPTURES" ] && export MI_VOLDIS_CAPTURES="$(cd "$CAPTURES" && pwd)"

SUMMARY=()
FAILED=0
LIMIT=()
[ -z "${GPU_CHECK_TIMEOUT:-}" ] || LIMIT=(timeout "$GPU_CHECK_TIMEOUT")
pack() {  # OUT, without grids and checkpoints, into GPU_CHECK_ARCHIVE (when set)
    [ -z "${GPU_CHECK_ARCHIVE:-}" ] && return 0
    tar -C "$DEST" --exclude='*.npz' --exclude=checkpoints -czf "$GPU_CHECK_ARCHIVE.partial" . &&
        mv "$GPU_CHECK_ARCHIVE.partial" "$GPU_CHECK_ARCHIVE"
}
step() {  # step NAME COMMAND...: print the command, run it (output to the terminal and OUT/NAME.log)
    local name=$1
    shift
    case " $STEPS " in *" $name "*) ;; *) return 0 ;; esac
    say "+ [$name] MI_VOLDIS_VARIANT=$MI_VOLDIS_VARIANT $*"
    local t0=$SECONDS
    if declare -F "$1" > /dev/null; then  # a function of this script limits its own commands
        "$@" 2>&1 | tee "$DEST/$name.log"
    else
        "${LIMIT[@]}" "$@" 2>&1 | tee "$DEST/$name.log"
    fi
    local rc=${PIPESTATUS[0]}
    SUMMARY+=("$name: exit $rc in $((SECONDS - t0)) s: $*")
    [ "$rc" -eq 0 ] || FAILED=$((FAILED + 1))
    pack
}

env_info() {  # the versions, the GPU, and whether OpenCV has its contrib modules
    "$PYTHON" -c 'import platform, mitsuba as mi, drjit as dr, cv2
print("python", platform.python_version(), "mitsuba", mi.__version__, "drjit", dr.__version__, "opencv",
      cv2.__version__, "with contrib" if hasattr(cv2, "xphoto") else "without contrib", "cuda backend",
      bool(dr.has_backend(dr.JitBackend.CUDA)))' || return 1
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv || echo "nvidia-smi: none"
}
captures() {  # the default command on each capture, all at once; fails if any fit fails
    local name pids=() rc=0
    for name in "${CAPTURE_NAMES[@]}"; do
        "${LIMIT[@]}" "$PYTHON" scripts/train.py "$CAPTURES/$name" --out "$DEST/captures/$name" --variant "$VARIANT" \
            > "$DEST/captures_$name.log" 2>&1 &
        pids+=("$!")
    done
    for pid in "${pids[@]}"; do wait "$pid" || rc=1; done
    for name in "${CAPTURE_NAMES[@]}"; do echo "== $name"; tail -n 5 "$DEST/captures_$name.log"; done
    return "$rc"
}

step env env_info
step tests "$PYTHON" -m pytest -q -rfEs -p no:cacheprovider "${TESTS[@]}"
step profile bash -o pipefail -c "\"$PYTHON\" scripts/bench.py --step-profile --batch $BATCHES --variant $VARIANT | tee \"$DEST/step_profile.json\""
step captures captures
step quick "$PYTHON" scripts/bench.py --quick --variant "$VARIANT" --work "$TMP/gpu_check_bench" --report "$DEST/report"

say ""
say "gpu_check: $VARIANT, outputs in $DEST${GPU_CHECK_ARCHIVE:+ (packed into $GPU_CHECK_ARCHIVE)}"
for line in "${SUMMARY[@]}"; do say "  $line"; done
pack
exit "$FAILED"
