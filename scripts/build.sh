#!/usr/bin/env bash
# Configures and builds one build folder, quietly: CMake's and the compiler's output go to
# BUILD/build.log and are shown only when something fails. A folder configured for another
# source tree (a build/ copied from another clone) is configured anew, said in one line.
#
#   scripts/build.sh BUILD [TARGET...] [-- CMAKE_OPTION...]     (no TARGET: everything)
set -euo pipefail
build=$1
shift
targets=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do
  targets+=("$1")
  shift
done
[ "${1:-}" = "--" ] && shift

cache="$build/CMakeCache.txt"
if [ -f "$cache" ]; then
  home=$(sed -n 's/^CMAKE_HOME_DIRECTORY:INTERNAL=//p' "$cache")
  if [ "$home" != "$(pwd -P)" ]; then
    echo "build: $build was configured for $home: configuring it anew for $(pwd -P)" >&2
    rm -rf "$cache" "$build/CMakeFiles"
  fi
fi
if [ ! -f "$cache" ]; then
  what=${targets[*]:-everything}
  what=${what/tools/psim and psweep}
  echo "build: configuring $build and building $what (the first time takes minutes:" \
    "README.md, 'The two commands')" >&2
fi
mkdir -p "$build"
# A build folder this user cannot write (root built it, a grader who is not root runs make
# grade): its programs are used as they are, said in one line, where they once failed with
# `build/build.log: Permission denied`.
if [ -f "$cache" ] && [ ! -w "$build" ]; then
  echo "build: $build is not writable by $(id -un): its programs are used as built (BUILD=DIR" \
    "builds into a folder of yours)" >&2
  exit 0
fi
log="$build/build.log"
# One build at a time per folder: two `make grade` at once on one checkout once both rebuilt it.
exec 9>>"$build/.build.lock"
if ! flock -n 9; then
  echo "build: another build of $build is under way: waiting for it" >&2
  flock 9
fi
if ! { cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release "$@" &&
  cmake --build "$build" -j "${JOBS:-$(nproc)}" ${targets[@]:+--target "${targets[@]}"}; } \
  >"$log" 2>&1; then
  # The compiler's first errors, else the end of the log.
  if grep -q -E '(error|Error)' "$log"; then
    grep -E -A8 '(error|Error)' "$log" | head -60 >&2
  else
    tail -n 40 "$log" >&2
  fi
  echo "build: failed; the whole output is in $log" >&2
  exit 1
fi
