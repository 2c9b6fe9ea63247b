#!/usr/bin/env bash
# make test-slurm: real Slurm runs of a sweep, end to end, on a private cluster of three nodes on
# this machine (n1, n2, n3 with 1, 1 and 2 CPUs: scripts/slurm/local_cluster.sh).
#   1. installs slurm-wlm and munge if missing (scripts/bootstrap.sh)
#   2. sweeps tests/slurm/tiny.json locally: the reference
#   3. a clean sweep: the same config as a 3-shard job array plus the merge job
#      (scripts/slurm/submit.sh); check_merged.py checks that the merged folder holds exactly the
#      local sweep's runs and state hashes, each once, that Slurm's job records put the shards on
#      two nodes or more, and that runs.csv and meta.json name the node of every row
#   4. ranks across nodes: tests/slurm/ranks.json, the mpi engine at P = 4 started by the config's
#      own launcher, run by psweep inside one allocation of the three nodes (sbatch -N 3 -n 4);
#      check_ranks.py checks that its ranks counted two nodes or more, as Slurm's record does, and
#      that its state hash is the local sweep's brute run's on the same scene
#   5. a node lost mid-sweep: the same again, but once a shard has written a row, its node's
#      slurmd and processes are killed (local_cluster.sh kill-node) and the node marked down, as an
#      administrator would; Slurm requeues the shard on another node, where it resumes from its
#      rows; the same checks, and the shard's first rows name the lost node, the rest the new one
#   6. a class graded (tests/slurm/make_class.py: 47 submissions, correct copies, tests/check's
#      broken builds, byte-identical wrong copies, a hang, a crash, two hostile ones): first here
#      by `make grade`'s tool, before the cluster starts; then through Slurm as 3 shards in
#      timing windows of 4 (scripts/slurm/grade.sh) with node n1 capped at 15% of a CPU
#      (local_cluster.sh slow-node), and check_graded.py wants every verdict and judging point
#      identical, the speed points within their stated spread although n1's raw times are not,
#      the class report's counts grades.csv's, each submission graded on its task's node and the
#      hostile ones contained
#   7. (the node lost in 5 back in service: local_cluster.sh revive-node) the same class again, a node lost mid-grading once a task has finished a timing window:
#      the task requeued elsewhere keeps that window (its grades are final), resumes its judging
#      runs and times the rest there; the same checks
# The daemons are stopped by their pid files whatever happens (an EXIT trap). The whole test has a
# deadline (TEST_SLURM_LIMIT_S, 900 s): a wait that outlives it fails with the jobs' records and the
# daemons' logs. Needs root (the cluster runs SlurmUser=root) or sudo. The work folder is removed
# on success and kept on failure. BUILD=DIR picks the build.
set -euo pipefail
cd "$(dirname "$0")/../.."
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "test-slurm: needs root or sudo (the cluster runs as root)" >&2; exit 2; }
  exec sudo --preserve-env=BUILD,TEST_SLURM_LIMIT_S "$0" "$@"
fi
scripts/bootstrap.sh slurm-wlm munge
build=${BUILD:-build}
config=tests/slurm/tiny.json
shards=3
started=$SECONDS
deadline=$((SECONDS + ${TEST_SLURM_LIMIT_S:-900}))

work=$(mktemp -d /tmp/particle-lab-slurm.XXXXXX)
chmod 755 "$work"  # munged runs as user munge and must reach its socket inside
ok=0
finish() {
  scripts/slurm/local_cluster.sh stop "$work/cluster" || true
  if [ $ok -eq 1 ]; then rm -rf "$work"; else echo "test-slurm: FAILED; logs in $work" >&2; fi
}
trap finish EXIT
trap 'exit 130' INT TERM  # so that the EXIT trap runs on a signal too

fail() {
  echo "test-slurm: FAIL: $*" >&2
  {
    squeue
    sinfo -N -o '%N %c %T %E'
    scontrol -o show job
    for log in "$work"/cluster/slurmctld.log "$work"/cluster/n*/slurmd.log "$work"/*/slurm/*.out \
      "$work"/*.log; do
      echo "--- $log, last lines"
      tail -n 15 "$log"
    done
  } >&2 2>&1 || true
  exit 1
}

wait_for() {  # wait_for WHAT COMMAND...: polls COMMAND every 0.2 s until the test's deadline
  local what=$1
  shift
  until "$@"; do
    [ $SECONDS -lt $deadline ] || fail "$what: not within TEST_SLURM_LIMIT_S=${TEST_SLURM_LIMIT_S:-900}s"
    sleep 0.2
  done
}

submit() {  # submit NAME: the config as a job array into $work/NAME; sets $array and $merge
  scripts/slurm/submit.sh "$config" "$work/$1" "$shards" "$build"
  read -r array merge <"$work/$1/slurm/jobs"
}

jobs_ended() { ! squeue -h -j "$array,$merge" -o %A | grep -q .; }

check() {  # check NAME [--lost NODE]: waits for the jobs, then judges the results against Slurm's records
  wait_for "the end of the $1 sweep's jobs" jobs_ended
  scontrol -o show job "$merge" | grep -q JobState=COMPLETED || fail "the $1 sweep's merge job did not complete"
  scontrol -o show job "$array" >"$work/$1/records"
  /usr/bin/python3 tests/slurm/check_merged.py "$work/local" "$work/$1" "$work/$1/records" "${@:2}" ||
    fail "the $1 sweep's results"
}

# Sets $lost_task and $lost_node to a running shard that has recorded a row, and its node.
running_shard_with_a_row() {
  while read -r lost_task lost_node; do
    local runs=$work/lost/shard-$lost_task/runs.csv
    [ -s "$runs" ] && [ "$(wc -l <"$runs")" -ge 2 ] && return 0
  done < <(squeue -h -j "$array" -t RUNNING -o '%K %N')
  return 1
}

requeued() {
  local record
  record=$(scontrol -o show job "${array}_$lost_task")
  [[ $record != *JobState=COMPLETED* ]] ||
    fail "shard $lost_task ended before its node was lost: $config is too short for this test"
  [[ $record == *JobState=PENDING* && $record != *Restarts=0* ]]
}

echo "test-slurm: local reference sweep" >&2
timeout $((deadline - SECONDS)) "$build/psweep" "$config" --out "$work/local" 2>"$work/local.log" ||
  fail "the local sweep: $(tail -n 5 "$work/local.log")"

echo "test-slurm: a class graded here" >&2
/usr/bin/python3 tests/slurm/make_class.py "$build" "$work/class/subs" "$work/class/grade.json" \
  "$work/class/victims.json" || fail "make_class.py"
grade_start=$SECONDS
timeout $((deadline - SECONDS)) /usr/bin/python3 -m analysis grade "$work/class/subs" \
  --out "$work/graded-here" --config "$work/class/grade.json" --psweep "$build/psweep" \
  >/dev/null 2>"$work/graded-here.log" || fail "make grade of the class: $(tail -n 5 "$work/graded-here.log")"
grade_here_s=$((SECONDS - grade_start))

timeout 90 scripts/slurm/local_cluster.sh start "$work/cluster" 3 || fail "the cluster did not start"
export SLURM_CONF=$work/cluster/slurm.conf

echo "test-slurm: a clean sweep" >&2
submit clean
check clean

echo "test-slurm: ranks across nodes" >&2
mkdir -p "$work/ranks/slurm"  # its log where fail() looks
ranks_job=$(sbatch --parsable -N 3 -n 4 --job-name=psweep-ranks -o "$work/ranks/slurm/ranks.out" \
  --wrap "exec $build/psweep tests/slurm/ranks.json --out $work/ranks") || fail "sbatch of the ranks run"
ranks_ended() { ! squeue -h -j "$ranks_job" -o %A | grep -q .; }
wait_for "the end of the ranks run" ranks_ended
scontrol -o show job "$ranks_job" >"$work/ranks/record"
/usr/bin/python3 tests/slurm/check_ranks.py "$work/local" "$work/ranks" "$work/ranks/record" ||
  fail "the ranks run across nodes"

# lose WHAT FINDER: once FINDER has set $lost_task and $lost_node (a running task and its node),
# kills that node, marks it down as an administrator would, and starts the requeued task at once.
lose() {
  wait_for "$1" "$2"
  timeout 30 scripts/slurm/local_cluster.sh kill-node "$work/cluster" "$lost_node" || fail "kill-node $lost_node"
  scontrol update nodename="$lost_node" state=down reason="test-slurm: node lost" || fail "$lost_node not marked down"
  wait_for "the requeue of task $lost_task" requeued
  # Slurm sets a requeued job's BeginTime two minutes ahead; the lost node's processes are dead
  # already, and the test's time is short.
  scontrol update jobid="${array}_$lost_task" starttime=now || fail "task $lost_task not released"
}

echo "test-slurm: a node lost mid-sweep" >&2
submit lost
lose "a running shard's first row" running_shard_with_a_row
check lost --lost "$lost_node"

grade_submit() {  # grade_submit NAME: the class through Slurm into $work/NAME; sets $array and $merge
  WINDOW=4 scripts/slurm/grade.sh "$work/class/subs" "$work/$1" 3 "$work/class/grade.json" "$build" \
    2>"$work/$1.log" || fail "grade.sh: $(tail -n 5 "$work/$1.log")"
  read -r array merge <"$work/$1/slurm/jobs"
}

grade_check() {  # grade_check NAME [--lost NODE]
  wait_for "the end of the $1 grading's jobs" jobs_ended
  scontrol -o show job "$merge" | grep -q JobState=COMPLETED || fail "the $1 grading's merge job did not complete"
  scontrol -o show job "$array" >"$work/$1/records"
  /usr/bin/python3 tests/slurm/check_graded.py "$work/graded-here" "$work/$1" "$work/$1/records" \
    "$work/class/victims.json" "${@:2}" || fail "the $1 grading's results"
}

# Sets $lost_task and $lost_node to a running task that has finished a timing window and has
# another to time, and its node.
running_task_with_a_window() {
  while read -r lost_task lost_node; do
    local shard=$work/glost/shard-$lost_task windows
    windows=$(ls "$shard"/timing/w-*/done 2>/dev/null | wc -l)
    [ "$windows" -ge 1 ] && [ ! -e "$shard/timing/w-$((windows + 1))/done" ] &&
      [ ! -e "$shard/done" ] && return 0
  done < <(squeue -h -j "$array" -t RUNNING -o '%K %N')
  return 1
}

timeout 90 scripts/slurm/local_cluster.sh revive-node "$work/cluster" "$lost_node" || fail "revive-node $lost_node"
echo "test-slurm: the class through Slurm, n1 slowed (made grade took ${grade_here_s} s here)" >&2
scripts/slurm/local_cluster.sh slow-node "$work/cluster" n1 15 || fail "slow-node n1"
grade_start=$SECONDS
grade_submit gclean
grade_check gclean --slow n1
echo "test-slurm: the class graded through Slurm in $((SECONDS - grade_start)) s, here in ${grade_here_s} s" >&2

echo "test-slurm: the class again, a node lost mid-grading" >&2
grade_submit glost
lose "a running task's first timing window" running_task_with_a_window
grade_check glost --lost "$lost_node"

echo "test-slurm: passed in $((SECONDS - started)) s" >&2
ok=1
