#!/usr/bin/env bash
# Soak test of the Slurm cancel/resubmit test (issue: "passes 20 times in a row under a CPU
# hog"): runs it N times (default 20) with one core kept busy, stops at the first failure.
# Usage: scripts/soak_slurm_cancel.sh [N]   (from the repository, after `make install`;
# no other Slurm test may run on the machine meanwhile: the test cluster is machine-wide)
set -u
cd "$(dirname "$0")/.."
runs=${1:-20}
.venv/bin/python -c "while True: pass" &
hog=$!
trap 'kill $hog' EXIT
for i in $(seq 1 "$runs"); do
  start=$(date +%s)
  log=$(mktemp)
  if .venv/bin/python -m pytest -q -p no:cacheprovider \
      "tests/slurm/test_slurm_integration.py::test_array_analysis_cancel_and_resubmit" >"$log" 2>&1; then
    echo "run $i passed in $(( $(date +%s) - start )) s"
  else
    echo "run $i FAILED after $((i - 1)) passes"; tail -40 "$log"; exit 1
  fi
  rm -f "$log"
done
echo "$runs of $runs passed under a CPU hog"
