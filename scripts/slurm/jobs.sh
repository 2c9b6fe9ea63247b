#!/usr/bin/env bash
# Sourced by the submit scripts of `make sweep-slurm` (submit.sh) and `make grade-slurm`
# (grade.sh): one job array of SHARDS tasks and a merge job that runs after every task succeeded.
#
#   submit_jobs OUT SHARDS CPUS TASK_SBATCH TASK_ARGS MERGE_SBATCH MERGE_ARGS
#
# TASK_ARGS and MERGE_ARGS name bash arrays of the scripts' arguments. Each task gets CPUS as
# --cpus-per-task, whole nodes with EXCLUSIVE=1 (--exclusive: no other job disturbs the
# timings); Slurm's own variables choose the rest (SBATCH_PARTITION, SBATCH_TIMELIMIT, ...).
# The logs go to OUT/slurm/shard-I.out and merge.out, "ARRAY_JOB_ID MERGE_JOB_ID" to
# OUT/slurm/jobs; sets $array and $merge.
submit_jobs() {
  local out=$1 shards=$2 cpus=$3 task=$4 merge_script=$6
  local -n task_argv=$5 merge_argv=$7
  command -v sbatch >/dev/null || { echo "submit: sbatch not found; run this on a Slurm login node" >&2; exit 2; }
  mkdir -p "$out/slurm"
  local exclusive=()
  [ "${EXCLUSIVE:-0}" = 0 ] || exclusive=(--exclusive)
  array=$(sbatch --parsable --array="1-$shards" --cpus-per-task="$cpus" \
    "${exclusive[@]}" --output="$out/slurm/shard-%a.out" "$task" "${task_argv[@]}")
  array=${array%%;*}
  merge=$(sbatch --parsable --dependency="afterok:$array" --output="$out/slurm/merge.out" \
    "$merge_script" "${merge_argv[@]}")
  merge=${merge%%;*}
  echo "$array $merge" >"$out/slurm/jobs"
  echo "submitted job array $array (shards 1-$shards, $cpus CPUs each${exclusive:+, exclusive nodes})" \
    "and merge job $merge (after all shards succeed); results in $out, logs in $out/slurm"
}
