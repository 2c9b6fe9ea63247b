#!/usr/bin/env bash
# `make grade-slurm`: a class of submissions graded over a Slurm cluster, and returns (the jobs
# run on the cluster):
#   scripts/slurm/grade.sh DIR OUT SHARDS [CONFIG [BUILD]]
# `analysis grade-slurm plan` draws the class's judging scenes and seeds into OUT, refuses a bad
# grade config (exit 2, before anything is submitted) and splits the class into SHARDS groups
# balanced by the grading's estimate (OUT/grade-slurm.json); then a job array of SHARDS tasks
# (grade.sbatch: each grades its group on its node) and a merge job after them all
# (grade-merge.sbatch: the one OUT `make grade` writes, and OUT/nodes.csv). Each task gets the
# largest T of the grading as --cpus-per-task, whole nodes with EXCLUSIVE=1. DRY_RUN=1 says the
# split and the node-hours and submits nothing. WINDOW=n: submissions per timing window
# (default 8). Run it on a login node, on a filesystem the nodes share (DIR, OUT, BUILD and
# this repository).
set -euo pipefail
[ $# -ge 3 ] && [ $# -le 5 ] || { echo "usage: $0 DIR OUT SHARDS [CONFIG [BUILD]]" >&2; exit 2; }
cd "$(dirname "$0")/../.."
dir=$(realpath -m "$1") out=$(realpath -m "$2") shards=$3
config=$(realpath -m "${4:-configs/grade.json}") build=$(realpath -m "${5:-build}")
[[ $shards =~ ^[1-9][0-9]*$ ]] || { echo "grade-slurm: SHARDS must be a positive integer, not '$shards'" >&2; exit 2; }
plan=(/usr/bin/python3 -m analysis grade-slurm plan "$dir" --out "$out" --shards "$shards"
  --config "$config" --psweep "$build/psweep" ${WINDOW:+--window "$WINDOW"} ${UNCONFINED:+--unconfined})
if [ "${DRY_RUN:-0}" != 0 ]; then
  exec "${plan[@]}" --dry-run
fi
command -v sbatch >/dev/null || { echo "grade-slurm: sbatch not found; run this on a Slurm login node (DRY_RUN=1 needs none)" >&2; exit 2; }
mkdir -p "$out"
"${plan[@]}"
cpus=$(/usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["cpus"])' "$out/grade-slurm.json")
# shellcheck source=scripts/slurm/jobs.sh
source scripts/slurm/jobs.sh
task_args=("$out")
merge_args=("$out")
submit_jobs "$out" "$shards" "$cpus" scripts/slurm/grade.sbatch task_args scripts/slurm/grade-merge.sbatch merge_args
echo "progress: /usr/bin/python3 -m analysis grade-slurm progress $out"
