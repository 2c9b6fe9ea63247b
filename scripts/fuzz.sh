#!/usr/bin/env bash
# Runs each libFuzzer target of tests/fuzz for SECONDS (make fuzz). Usage: fuzz.sh BUILD SECONDS
# [RUNS]: with RUNS (> 0) each target stops after that many inputs, SECONDS only a cap, so that
# with FUZZ_SEED and an empty BUILD/corpus the inputs tried are the same from run to run (for a
# build at another path they still differ: docs/testing.md, "Fuzzing").
# The working corpus grows in BUILD/corpus/<target>; the seeds are the committed hand-made inputs
# of tests/fuzz/corpus/<target> plus the repository's scenes/ or configs/ (read, never written).
# A crash leaves its input as BUILD/crash-<target>-<hash> and fails the run.
set -euo pipefail
cd "$(dirname "$0")/.."
build=$1 seconds=$2 runs=${3:-0}
[ "$runs" -gt 0 ] || runs=-1  # libFuzzer: -1, no limit
# The same inputs on every run: no address-space randomization, which moved one edge of
# fuzz_config's coverage from run to run (setarch -R, where the machine allows it), and no
# reloading of the corpus folder on a timer (-reload=0). Without randomization the stack starts
# where the environment ends, so its size moves addresses too: the same commit tried other
# inputs under make than from a shell, and others again in CI's environment (728, 703 and 672
# fuzz_scene inputs). The fuzzers run in an environment of their own (env -i), with relative
# paths only on their command line.
fixed=(env -i PATH=/usr/bin:/bin)
if setarch -R true 2>/dev/null; then
  fixed=(setarch -R "${fixed[@]}")
else
  echo "fuzz: setarch -R is refused here: addresses are randomized, and the inputs tried may differ from run to run" >&2
fi
status=0
for pair in scene:scenes config:configs; do
  target=${pair%%:*} seeds=${pair#*:}
  mkdir -p "$build/corpus/$target"
  log="$build/fuzz_$target.log"
  echo "fuzz_$target: $([ "$runs" -gt 0 ] && echo "$runs inputs, at most ")${seconds}s (log: $log)"
  # -timeout: one input taking seconds is a hang; -rss_limit_mb: an allocation without bound.
  # FUZZ_SEED (0: libFuzzer picks one) fixes the inputs tried, so CI's verdict is the code's.
  if "${fixed[@]}" "$build/fuzz_$target" -seed="${FUZZ_SEED:-0}" -max_total_time="$seconds" \
      -runs="$runs" -reload=0 -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$build/crash-$target-" \
      "$build/corpus/$target" "tests/fuzz/corpus/$target" "$seeds" >"$log" 2>&1; then
    grep -E '^stat::number_of_executed_units|^Done' "$log" | tr '\n' ' '; echo
  else
    status=1
    echo "fuzz_$target FAILED:" >&2
    tail -40 "$log" >&2
  fi
done
exit $status
