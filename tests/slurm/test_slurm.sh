#!/usr/bin/env bash
# make test-slurm: a real Slurm run of a sweep, end to end, on a single-node cluster on localhost.
#   1. installs slurm-wlm and munge if missing (scripts/bootstrap.sh)
#   2. sweeps tests/slurm/tiny.json locally (the reference)
#   3. starts a private cluster (scripts/slurm/local_cluster.sh), submits the same config as a
#      2-shard job array plus the dependent merge job (scripts/slurm/submit.sh), waits for both
#   4. checks that the merged folder has exactly the local sweep's configurations, repetitions and
#      state hashes, and the shards' hosts and Slurm ids in meta.json (check_merged.py)
# The cluster's daemons are stopped by their pid files whatever happens (an EXIT trap). Needs root
# (the cluster runs SlurmUser=root) or sudo. The work folder is removed on success and kept, with
# the daemons' logs, on failure. BUILD=DIR picks the build.
set -euo pipefail
cd "$(dirname "$0")/../.."
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "test-slurm: needs root or sudo (the cluster runs as root)" >&2; exit 2; }
  exec sudo --preserve-env=BUILD "$0" "$@"
fi
scripts/bootstrap.sh slurm-wlm munge
build=${BUILD:-build}
config=tests/slurm/tiny.json
limit_s=${TEST_SLURM_LIMIT_S:-300}

work=$(mktemp -d /tmp/particle-lab-slurm.XXXXXX)
chmod 755 "$work"  # munged runs as user munge and must reach its socket inside
ok=0
finish() {
  scripts/slurm/local_cluster.sh stop "$work/cluster" || true
  if [ $ok -eq 1 ]; then rm -rf "$work"; else echo "test-slurm: FAILED; logs in $work" >&2; fi
}
trap finish EXIT
trap 'exit 130' INT TERM  # so that the EXIT trap runs on a signal too

started=$SECONDS
echo "test-slurm: local reference sweep" >&2
"$build/psweep" "$config" --out "$work/local" 2>"$work/local.log"

scripts/slurm/local_cluster.sh start "$work/cluster"
export SLURM_CONF=$work/cluster/slurm.conf
scripts/slurm/submit.sh "$config" "$work/slurm" 2 "$build"
read -r array merge <"$work/slurm/slurm/jobs"

# Wait for the merge job (it runs after both shards) to leave the queue.
deadline=$((SECONDS + limit_s))
while squeue -h -j "$array,$merge" -o %A 2>/dev/null | grep -q .; do
  if [ $SECONDS -ge $deadline ]; then
    echo "test-slurm: the jobs did not finish within ${limit_s}s:" >&2
    squeue >&2 || true
    exit 1
  fi
  sleep 0.5
done
state=$(scontrol show job "$merge" | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
if [ "$state" != COMPLETED ]; then
  echo "test-slurm: the merge job ended $state; its log:" >&2
  cat "$work/slurm/slurm/merge.out" >&2 || true
  for f in "$work"/slurm/slurm/shard-*.out; do echo "--- $f" >&2; cat "$f" >&2; done
  exit 1
fi
/usr/bin/python3 tests/slurm/check_merged.py "$work/local" "$work/slurm" "$array" "$merge"
echo "test-slurm: passed in $((SECONDS - started)) s" >&2
ok=1
