#!/usr/bin/env bash
# The second device call of 2026-11-27 (#42): the suite (the first call's run lacked the scenes' textures) beside
# fern and garden with the sample bound, on one GPU (run.sh does the work).
#
#   reports/experiments/2026-11-27/gpu/rerun.sh OUT CAPTURES     # from the checkout; carry .gpu and CAPTURES
GPU_RUN_FITS="fern:fern garden:garden" GPU_RUN_TESTS="-n 8 tests" GPU_RUN_LIMIT=330 \
    exec "$(dirname "$0")/run.sh" "$@"
