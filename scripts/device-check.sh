#!/usr/bin/env bash
# The checks that need the device machine (an NVIDIA H100 or H200 and 16 CPU cores), as one
# script for its 15 minutes: run there from the repository root with the kit that
# scripts/device-kit.sh packed here (make device-kit), writing under OUT (the device's $OUT, of
# which at most 8 files, two folders down, come back). Every step runs under `timeout`, the whole
# within 9 minutes, so that a hang cannot eat the budget of a rerun:
#   0. pre-flight (20 s): the driver answers (nvidia-smi), and one small run of the GPU engine
#      gives brute's state hash; without both, nothing else runs (exit 3);
#   1. the GPU engine's tests (150 s; tests/gpu: brute's state on the equivalence scenes, K = 1
#      and 16, every printed time unit; cells' at N = 200,000): a skipped test is a failure;
#   2. configs/gpu.json (210 s): the GPU engine beside auto at T = 16, families (a) and (b);
#   3. configs/threads16.json (150 s): brute and auto at T = 1 .. 16.
# The sweeps write into a work folder outside OUT; what comes back is OUT/machine.txt,
# OUT/summary.txt (each step's status and time, the ends of the logs), OUT/gpu_tests.xml and
# OUT/results.tar.gz (the sweeps' folders and every log). Each step runs whatever the one before
# gave, so one failure leaves the others' results. Exit 0 when every step passed.
# Usage: device-check.sh [KIT]   (KIT: device-kit)
set -uo pipefail
kit=${1:-device-kit} out=${OUT:?set OUT to the folder whose files come back}
export LD_LIBRARY_PATH="$PWD/$kit/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
work=$(mktemp -d "${TMPDIR:-/tmp}/device-check.XXXXXX")
summary="$out/summary.txt"
status=0
: > "$summary"

# step NAME SECONDS COMMAND...: runs it under timeout, its output in work/NAME.log, one line of
# status in the summary and the last lines of the log under it.
step() {
  local name=$1 limit=$2
  shift 2
  local start=$SECONDS rc
  # bash -c: a step may be a function of this script (exported below)
  timeout --kill-after=10 "$limit" bash -c '"$@"' "$name" "$@" > "$work/$name.log" 2>&1
  rc=$?
  local verdict=passed
  [ $rc -eq 0 ] || verdict="FAILED (exit $rc$([ $rc -eq 124 ] && echo ": timed out after ${limit} s"))"
  [ $rc -eq 0 ] || status=1
  echo "$name: $verdict in $((SECONDS - start)) s" | tee -a "$summary"
  tail -4 "$work/$name.log" | sed 's/^/    /' >> "$summary"
  return $rc
}

{ nproc; nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv; lscpu; } \
  > "$out/machine.txt" 2>&1

# 0. Pre-flight: the driver, then the GPU engine's state against brute's on 2,000 particles.
preflight() {
  nvidia-smi -L || return 1
  for engine in brute gpu; do
    printf '2000\n20000\n1\n20\nperf\n' |
      "$kit/psim" --engine "$engine" --metrics "$work/$engine.json" > /dev/null || return 1
  done
  local a b
  a=$(grep -o '"state_hash": *"[0-9a-f]*"' "$work/brute.json")
  b=$(grep -o '"state_hash": *"[0-9a-f]*"' "$work/gpu.json")
  echo "brute $a, gpu $b"
  [ -n "$a" ] && [ "$a" = "$b" ]
}
export kit out work
export -f preflight
if ! step preflight 20 preflight; then
  tar -czf "$out/results.tar.gz" -C "$work" . 2>/dev/null
  exit 3
fi

# 1. The GPU tests: a test skipped (no device, an old driver) is not a pass.
gpu_tests() {
  "$kit/gpu_tests" --gtest_output="xml:$out/gpu_tests.xml" || return 1
  ! grep -q '\[  SKIPPED \]' "$work/gpu_tests.log" || { echo "device-check: tests were skipped"; return 1; }
}
export -f gpu_tests
step gpu_tests 150 gpu_tests

# 2, 3. The sweeps, into the work folder.
step gpu 210 "$kit/psweep" configs/gpu.json --psim "$kit/psim" --out "$work/gpu" --yes
step threads16 150 "$kit/psweep" configs/threads16.json --psim "$kit/psim" --out "$work/threads16" --yes

tar -czf "$out/results.tar.gz" -C "$work" . 2>/dev/null
echo "device-check: $([ $status -eq 0 ] && echo passed || echo FAILED); results in $out" | tee -a "$summary"
exit $status
