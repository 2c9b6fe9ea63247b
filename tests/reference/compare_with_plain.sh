#!/usr/bin/env bash
# psim against the independent plain C implementation of the model: the same explicit scene
# (psim's step-0 lines of a random scene) must give byte-identical final states.
# Usage: compare_with_plain.sh PSIM PLAIN
set -euo pipefail
psim=$1 plain=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

check() {  # N L r S seed K engine threads
  local header="$1\n$2\n$3\n$4\nperf\n"
  printf "$header" | "$psim" --seed "$5" | awk -v n="$1" 'NR <= n { print $2, $3, $4, $5, $6 }' > "$work/particles"
  { printf "$header"; cat "$work/particles"; } > "$work/scene.in"
  "$plain" "$6" < "$work/scene.in" | tail -n "$1" > "$work/plain.out"
  "$psim" --slow-factor "$6" --engine "$7" --threads "$8" "$work/scene.in" | tail -n "$1" > "$work/psim.out"
  if ! cmp -s "$work/plain.out" "$work/psim.out"; then
    echo "MISMATCH for N=$1 L=$2 r=$3 S=$4 seed=$5 K=$6 engine=$7 T=$8" >&2
    diff "$work/plain.out" "$work/psim.out" | head -5 >&2
    exit 1
  fi
  echo "identical: N=$1 L=$2 r=$3 S=$4 seed=$5 K=$6 engine=$7 T=$8"
}

check 300 20000 1 300 3210 1 brute 1   # the 2019 kind of scene: sparse and fast
check 400 300 2 100 7 1 brute 2        # dense: many collisions, drops and overlaps
check 400 300 2 50 8 4 brute 2         # slow factor 4
# Every engine of the discrete model (not grid-unsafe, which drops collisions, nor event, which
# computes the exact continuous-time dynamics instead) that this psim can run here (gpu needs a
# device: without one psim refuses it, exit 2).
for engine in $("$psim" --list-engines | grep -v -x -e grid-unsafe -e event); do
  if ! printf '1\n10\n1\n0\nperf\n0 5 5 0 0\n' | "$psim" --engine "$engine" >/dev/null 2>&1; then
    echo "skipped: engine=$engine (psim cannot run it here)"
    continue
  fi
  check 400 300 2 50 9 1 "$engine" 3
done
