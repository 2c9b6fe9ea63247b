#!/usr/bin/env bash
# `make sweep-slurm`: submits a sweep to Slurm as a job array of SHARDS shards and a dependent
# merge job, and returns (the jobs run on the cluster):
#   scripts/slurm/submit.sh CONFIG OUT SHARDS [BUILD]
# Run it on a login node, from the repository, on a filesystem the compute nodes share (they run
# BUILD/psweep and write OUT/shard-I). Each task gets --cpus-per-task = the largest T of the sweep;
# EXCLUSIVE=1 asks for whole nodes (--exclusive), so other jobs do not disturb the timings. Slurm's
# own variables choose the rest, e.g. SBATCH_PARTITION, SBATCH_TIMELIMIT, SBATCH_ACCOUNT.
# Writes OUT/slurm/jobs ("ARRAY_JOB_ID MERGE_JOB_ID") and the jobs' logs to OUT/slurm/ (jobs.sh).
set -euo pipefail
[ $# -ge 3 ] && [ $# -le 4 ] || { echo "usage: $0 CONFIG OUT SHARDS [BUILD]" >&2; exit 2; }
cd "$(dirname "$0")/../.."
config=$(realpath "$1") out=$(realpath -m "$2") shards=$3 build=$(realpath "${4:-build}")
[[ $shards =~ ^[1-9][0-9]*$ ]] || { echo "submit: SHARDS must be a positive integer, not '$shards'" >&2; exit 2; }

# The sweep's largest thread count, from psweep's own expansion (which also validates the config).
count=$("$build/psweep" "$config" --dry-run --count)
threads=$(awk '$1 == "largest" && $2 == "T:" {print $3}' <<<"$count")
[ -n "$threads" ] || { echo "submit: psweep --dry-run --count gave no largest T" >&2; exit 1; }
echo "$count"

# shellcheck source=scripts/slurm/jobs.sh
source scripts/slurm/jobs.sh
task_args=("$config" "$out" "$shards" "$build")
merge_args=("$out" "$shards" "$build")
submit_jobs "$out" "$shards" "$threads" scripts/slurm/sweep.sbatch task_args scripts/slurm/merge.sbatch merge_args
