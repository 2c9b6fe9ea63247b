#!/usr/bin/env bash
# A private Slurm cluster of several nodes on one machine, for `make test-slurm`.
#
#   local_cluster.sh start DIR [NODES]   writes DIR/slurm.conf, starts munged, slurmctld and one
#                                        slurmd per node n1 .. nNODES (default 3) as root, and waits
#                                        until every node is idle; clients then need
#                                        SLURM_CONF=DIR/slurm.conf
#   local_cluster.sh kill-node DIR NODE  kills NODE's slurmd and everything its jobs run, at once,
#                                        as a lost machine would; Slurm lists the node as it was
#                                        until someone marks it down (scontrol update)
#   local_cluster.sh revive-node DIR NODE
#                                        starts a killed NODE's slurmd again and returns it to
#                                        service, as an administrator would once it is repaired
#   local_cluster.sh slow-node DIR NODE PERCENT
#                                        caps NODE at PERCENT of one CPU (a cgroup v1 CPU quota on
#                                        its slurmd, which every job step it starts inherits): a
#                                        slower machine, for the grading's fairness test
#   local_cluster.sh stop DIR            cancels the cluster's jobs and stops every daemon it started
#                                        by its pid file in DIR; safe in any state, and more than once
#
# The nodes differ as a real cluster's do: every third node has 2 CPUs, the others 1 (1, 1 and 2
# for three nodes); SlurmdParameters=config_overrides lets a node claim its count whatever this
# machine has. All of them share this machine's cores: the cluster proves correctness and
# recovery, never speed. Each node has its own port, and its spool, log and pid file in DIR/NODE/.
# Nothing is shared with a cluster the machine may already run: munged listens on its own socket
# in DIR (slurm.conf's AuthInfo points there), the daemons on unused ports. Needs root
# (SlurmUser=root, munged started as user munge) and Debian's slurm-wlm and munge.
set -euo pipefail

usage() {
  echo "usage: $0 start DIR [NODES] | kill-node DIR NODE | revive-node DIR NODE | slow-node DIR NODE PERCENT | stop DIR" >&2
  exit 2
}
[ $# -ge 2 ] || usage
action=$1
dir=$(realpath -m "$2")
conf=$dir/slurm.conf

# COUNT TCP ports nothing listens on (the kernel picks them; they are free again once closed).
free_ports() {
  /usr/bin/python3 - "$1" <<'PY'
import socket, sys
socks = [socket.socket() for _ in range(int(sys.argv[1]))]
for s in socks:
    s.bind(("127.0.0.1", 0))
print(" ".join(str(s.getsockname()[1]) for s in socks))
PY
}

wait_until() {  # wait_until SECONDS WHAT COMMAND...: polls COMMAND every 0.2 s
  local limit=$1 what=$2
  shift 2
  local deadline=$((SECONDS + limit))
  until "$@" >/dev/null 2>&1; do
    if [ $SECONDS -ge $deadline ]; then
      echo "local_cluster: $what did not happen within ${limit}s; logs in $dir" >&2
      return 1
    fi
    sleep 0.2
  done
}

# Whether any of the PIDs runs; a zombie has ended (some machines' init reaps late).
running() { ps -o stat= -p "$*" | grep -qv '^Z'; }
ended() { ! running "$@"; }
alive() { [ -s "$1" ] && running "$(cat "$1")"; }

no_jobs() { [ -z "$(squeue -h -o %A)" ]; }

all_idle() { ! sinfo -h -o %T | grep -qv '^idle$'; }

start() {
  local nodes=$1 i
  [[ $nodes =~ ^[1-9][0-9]?$ ]] || { echo "local_cluster: NODES must be 1 to 99, not '$nodes'" >&2; exit 2; }
  [ "$(id -u)" -eq 0 ] || { echo "local_cluster: start needs root" >&2; exit 2; }
  for exe in munged mungekey slurmctld slurmd sinfo; do
    command -v "$exe" >/dev/null || { echo "local_cluster: $exe missing (apt-get install slurm-wlm munge)" >&2; exit 2; }
  done
  if alive "$dir/slurmctld.pid"; then
    echo "local_cluster: a cluster already runs in $dir; stop it first" >&2
    exit 2
  fi
  mkdir -p "$dir"/munge "$dir"/state
  chmod 755 "$dir"  # munged runs as munge and must reach its socket folder
  chown munge:munge "$dir"/munge
  chmod 755 "$dir"/munge  # munged: clients need to reach the socket
  if [ ! -s /etc/munge/munge.key ]; then
    mungekey --create --keyfile=/etc/munge/munge.key
    chown munge:munge /etc/munge/munge.key
    chmod 600 /etc/munge/munge.key
  fi
  runuser -u munge -- /usr/sbin/munged --socket="$dir/munge/munge.socket" \
    --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" \
    --seed-file="$dir/munge/munged.seed"

  local ports
  read -r -a ports < <(free_ports $((nodes + 1)))
  cat >"$conf" <<CONF
# Written by scripts/slurm/local_cluster.sh: a private cluster of $nodes nodes on one machine, for tests.
ClusterName=particlelab
SlurmctldHost=localhost
SlurmctldPort=${ports[0]}
SlurmUser=root
SlurmdUser=root
SlurmdParameters=config_overrides
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
MinJobAge=3600
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/%n/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/%n/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/%n/slurmd.log
CONF
  for ((i = 1; i <= nodes; i++)); do
    mkdir -p "$dir/n$i/spool"
    echo "NodeName=n$i NodeAddr=127.0.0.1 Port=${ports[i]} CPUs=$((i % 3 ? 1 : 2)) State=UNKNOWN" >>"$conf"
  done
  echo "PartitionName=local Nodes=n[1-$nodes] Default=YES MaxTime=INFINITE State=UP" >>"$conf"

  export SLURM_CONF=$conf
  slurmctld -c -f "$conf"
  for ((i = 1; i <= nodes; i++)); do slurmd -f "$conf" -N "n$i"; done
  wait_until 60 "every node idle" all_idle
  echo "local_cluster: $nodes nodes up ($(sinfo -h -N -o '%N:%c' | paste -sd ' ') CPUs); export SLURM_CONF=$conf" >&2
}

# Stops PIDs and their descendants, each before its children are listed (a stopped process
# starts no other), and prints them.
stop_tree() {
  local pid
  for pid in "$@"; do
    kill -STOP "$pid" 2>/dev/null || continue
    echo "$pid"
    # shellcheck disable=SC2046  # one pid a word
    stop_tree $(pgrep -P "$pid")
  done
}

kill_node() {
  local node=$1 pidfile=$dir/$1/slurmd.pid job steps=()
  alive "$pidfile" || { echo "local_cluster: no slurmd of node '$node' runs in $dir" >&2; exit 2; }
  export SLURM_CONF=$conf
  # A job's steps run under slurmstepd processes that slurmd detached from itself.
  for job in $(squeue -h -w "$node" -o %A); do
    mapfile -t -O ${#steps[@]} steps < <(pgrep -f "^slurmstepd: \[$job\.")
  done
  # shellcheck disable=SC2046  # one pid a word
  kill -KILL $(stop_tree "$(cat "$pidfile")" "${steps[@]}")
  rm -f "$pidfile"
  echo "local_cluster: killed node $node (slurmd and ${#steps[@]} job steps)" >&2
}

# Sends TERM to the daemons of the PIDFILEs at once (each takes a second or two to end), then KILL
# to those alive after 10 s; forgets the pid files, stale ones too.
stop_daemons() {
  local pidfile pids=()
  for pidfile in "$@"; do
    if [ -s "$pidfile" ]; then pids+=("$(cat "$pidfile")"); fi
  done
  if [ ${#pids[@]} -gt 0 ] && kill -TERM "${pids[@]}" 2>/dev/null; then
    wait_until 10 "exit of pids ${pids[*]} ($*)" ended "${pids[@]}" ||
      kill -KILL "${pids[@]}" 2>/dev/null || true
  fi
  rm -f "$@"
}

revive_node() {
  local node=$1
  alive "$dir/$node/slurmd.pid" && { echo "local_cluster: node $node runs already" >&2; exit 2; }
  export SLURM_CONF=$conf
  # ReturnToService=2: the node, down, comes back once its slurmd registers with its config.
  slurmd -f "$conf" -N "$node"
  # (`sinfo -n NODE` read "mixed" here for a node whose killed job was requeued; the list did not)
  node_idle() { sinfo -h -N -o "%N %T" | grep -qx "$node idle"; }
  wait_until 60 "node $node idle" node_idle
  echo "local_cluster: node $node back in service" >&2
}

# The cgroup of a slowed node: named after DIR, so that two clusters never share one.
quota_group() { echo "/sys/fs/cgroup/cpu/particlelab-$(cksum <<<"$dir" | cut -d" " -f1)-$1"; }

slow_node() {
  local node=$1 percent=$2 pidfile=$dir/$1/slurmd.pid group
  [[ $percent =~ ^[1-9][0-9]?$ ]] || { echo "local_cluster: PERCENT must be 1 to 99, not '$percent'" >&2; exit 2; }
  alive "$pidfile" || { echo "local_cluster: no slurmd of node '$node' runs in $dir" >&2; exit 2; }
  [ -w /sys/fs/cgroup/cpu/cgroup.procs ] || { echo "local_cluster: no writable cgroup v1 cpu controller (/sys/fs/cgroup/cpu)" >&2; exit 2; }
  group=$(quota_group "$node")
  mkdir -p "$group"
  # A period of 10 ms rather than 100: a run of a few tens of milliseconds is throttled too.
  echo 10000 >"$group/cpu.cfs_period_us"
  echo $((percent * 100)) >"$group/cpu.cfs_quota_us"
  echo "$(cat "$pidfile")" >"$group/cgroup.procs"
  echo "local_cluster: node $node capped at $percent% of a CPU ($group)" >&2
}

stop() {
  if [ -f "$conf" ] && alive "$dir/slurmctld.pid"; then
    export SLURM_CONF=$conf
    # Every job of this private cluster is the test's own.
    # shellcheck disable=SC2046  # one job id a word
    scancel --full --quiet $(squeue -h -o %A 2>/dev/null) 2>/dev/null || true
    wait_until 20 "end of the cancelled jobs" no_jobs || true
  fi
  stop_daemons "$dir"/*/slurmd.pid
  stop_daemons "$dir/slurmctld.pid"
  stop_daemons "$dir/munge/munged.pid"
  # A slowed node's cgroup goes once its processes have ended.
  local group
  for group in "$(quota_group "")"*; do
    [ -d "$group" ] && { rmdir "$group" 2>/dev/null || echo "local_cluster: $group still holds processes" >&2; }
  done
  return 0
}

case $action in
  start) [ $# -le 3 ] || usage; start "${3:-3}" ;;
  kill-node) [ $# -eq 3 ] || usage; kill_node "$3" ;;
  slow-node) [ $# -eq 4 ] || usage; slow_node "$3" "$4" ;;
  revive-node) [ $# -eq 3 ] || usage; revive_node "$3" ;;
  stop) [ $# -eq 2 ] || usage; stop ;;
  *) usage ;;
esac
