#!/usr/bin/env bash
# Run the whole suite RUNS times in a row, with BURNERS CPU-burning processes
# alongside (0: an idle machine); stop at the first failing run.
#   tools/repeat_tests.sh 5 0     # five runs, idle
#   tools/repeat_tests.sh 3 2     # three runs, two cores kept busy
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-5}
burners=${2:-0}
pids=()
cleanup() { for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done; }
trap cleanup EXIT
for _ in $(seq 1 "$burners"); do
    python3 -c "while True: pass" &
    pids+=($!)
done
for run in $(seq 1 "$runs"); do
    started=$(date +%s)
    if ! make test PYTEST_ARGS="-q -rs -p no:cacheprovider" > "/tmp/mt_accuracy_run_${run}.log" 2>&1; then
        echo "run $run of $runs with $burners burners: FAILED (log /tmp/mt_accuracy_run_${run}.log)"
        tail -30 "/tmp/mt_accuracy_run_${run}.log"
        exit 1
    fi
    echo "run $run of $runs with $burners burners: $(tail -1 "/tmp/mt_accuracy_run_${run}.log") ($(( $(date +%s) - started )) s)"
done
