#!/usr/bin/env bash
# Trim the bundle of ../shared/tools/gpu_bundle.sh (Mitsuba / Dr.Jit for the lent GPU machine's Python 3.12) to
# what this project loads, so that real captures fit beside it under the 64 MiB a device call may carry:
#
#   ../shared/tools/gpu_bundle.sh .gpu && scripts/gpu_bundle_slim.sh [.gpu/site312.tar.xz [.gpu-slim/site312.tar.xz]]
#
# Leaves out Dr.Jit's C++ headers, the spectral upsampling table and the sun-sky data (spectral variants and
# the sunsky emitter only), and plugins no scene, test or script here names (curves, ellipsoids, SDF grids,
# hair, measured and principled BSDFs, polarisers, the particle tracer, volpathmis, the sky emitters): 34 MiB
# -> 21 MiB. Writes a new file (refused where one is already there) in a folder it adds to .git/info/exclude;
# carry that folder alone, and point scripts/gpu_check.sh at it: GPU_BUNDLE=.gpu-slim/site312.tar.xz.
set -euo pipefail
BUNDLE=${1:-.gpu/site312.tar.xz}
OUT=${2:-.gpu-slim/site312.tar.xz}
[ -f "$BUNDLE" ] || { echo "gpu_bundle_slim: no bundle at $BUNDLE (make it with ../shared/tools/gpu_bundle.sh)" >&2; exit 1; }
[ ! -e "$OUT" ] || { echo "gpu_bundle_slim: $OUT is already there: remove it first to make it again" >&2; exit 1; }
WORK=$(mktemp -d)
PACKED=$(mktemp)
trap 'rm -rf "$WORK" "$PACKED"' EXIT
tar -C "$WORK" -xJf "$BUNDLE"
[ -d "$WORK/mitsuba/plugins" ] || { echo "gpu_bundle_slim: $BUNDLE holds no mitsuba/plugins" >&2; exit 1; }
rm -rf "$WORK/drjit/include" "$WORK/mitsuba/data/srgb.coeff" "$WORK/mitsuba/data/sunsky"
for p in ellipsoids ellipsoidsmesh bsplinecurve linearcurve sdfgrid sunsky timed_sunsky hair measured \
         measured_polarized principled principledthin pplastic ptracer volpathmis polarizer retarder \
         linearpolarizer blender; do
    rm -f "$WORK/mitsuba/plugins/$p.so"
done
DIR=$(dirname "$OUT")
mkdir -p "$DIR"
case "$DIR" in /* | . | ..*) INSIDE= ;; *) INSIDE=1 ;; esac  # a folder of the checkout: ignored by git
if [ -n "$INSIDE" ] && git rev-parse --git-dir > /dev/null 2>&1; then
    EXCLUDE="$(git rev-parse --git-dir)/info/exclude"
    mkdir -p "$(dirname "$EXCLUDE")"
    grep -qx "/${DIR#./}/" "$EXCLUDE" 2>/dev/null || echo "/${DIR#./}/" >> "$EXCLUDE"
fi
tar -C "$WORK" -cf - . | xz -9e -T2 > "$PACKED"
mv "$PACKED" "$OUT" && chmod 644 "$OUT"  # mktemp made it private
du -h "$OUT"
