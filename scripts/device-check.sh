#!/usr/bin/env bash
# The checks that need the device machine (an NVIDIA H100 or H200 and 16 CPU cores), as one
# script for its 15 minutes: run there from the repository root with the kit that
# scripts/device-kit.sh packed here (make device-kit), writing under OUT (the device's $OUT):
#   1. the GPU engine's tests (tests/gpu: brute's state on the equivalence scenes, K = 1 and 16,
#      every printed time unit; cells' at N = 200,000): OUT/gpu_tests.{log,xml};
#   2. configs/gpu.json: the GPU engine beside auto at T = 16, families (a) and (b): OUT/gpu/;
#   3. configs/threads16.json: brute and auto at T = 1 .. 16: OUT/threads16/.
# Each step runs whatever the one before gave, so one failure leaves the others' results.
# Usage: device-check.sh [KIT]   (KIT: device-kit)
set -uo pipefail
kit=${1:-device-kit} out=${OUT:?set OUT to the folder whose files come back}
export LD_LIBRARY_PATH="$PWD/$kit/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
status=0
{ nproc; nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv; lscpu; } \
  > "$out/machine.txt" 2>&1
"$kit/gpu_tests" --gtest_output="xml:$out/gpu_tests.xml" > "$out/gpu_tests.log" 2>&1 || status=1
tail -3 "$out/gpu_tests.log"
for config in gpu threads16; do
  "$kit/psweep" "configs/$config.json" --psim "$kit/psim" --out "$out/$config" \
    > "$out/$config.log" 2>&1 || status=1
  tail -2 "$out/$config.log"
done
exit $status
