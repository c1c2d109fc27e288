#!/bin/bash
# waits for pid $1 (a worker), then runs queue.sh with the rest
while kill -0 $1 2>/dev/null; do sleep 20; done
shift
exec /work/runs/s68/bench/queue.sh "$@"
