#!/usr/bin/env bash
# The third device call of 2026-11-27 (#42): the default command on the statue alone on one GPU (its row was
# never finished there), inside what was left of the session's device time (run.sh does the work).
#
#   reports/experiments/2026-11-27/gpu/statue.sh OUT CAPTURES     # from the checkout; carry .gpu and CAPTURES
GPU_RUN_FITS="statue:statue" GPU_RUN_TESTS="" GPU_RUN_LIMIT=260 exec "$(dirname "$0")/run.sh" "$@"
