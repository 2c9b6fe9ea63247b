#!/usr/bin/env bash
# A single-node Slurm cluster on localhost, private to one folder, for `make test-slurm`.
#
#   local_cluster.sh start DIR   writes DIR/slurm.conf and starts munged, slurmctld and slurmd
#                                (as root), waits until the node is idle; clients then need
#                                SLURM_CONF=DIR/slurm.conf
#   local_cluster.sh stop DIR    cancels the cluster's jobs and stops the three daemons by their
#                                pid files in DIR; safe to call in any state, and more than once
#
# Nothing is shared with a cluster the machine may already run: munged listens on its own socket in
# DIR (slurm.conf's AuthInfo points there), the Slurm daemons on two unused ports, with their state,
# spool, logs and pid files in DIR. Needs root (SlurmUser=root, munged started as user munge) and
# Debian's slurm-wlm and munge.
set -euo pipefail

usage() { echo "usage: $0 start|stop DIR" >&2; exit 2; }
[ $# -eq 2 ] || usage
action=$1
dir=$(realpath -m "$2")

# Two TCP ports nothing listens on (the kernel picks them; they are free again once closed).
free_ports() {
  /usr/bin/python3 - <<'PY'
import socket
socks = [socket.socket() for _ in range(2)]
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

node_idle() { [ "$(sinfo -h -n localhost -o %T 2>/dev/null)" = idle ]; }

start() {
  [ "$(id -u)" -eq 0 ] || { echo "local_cluster: start needs root" >&2; exit 2; }
  for exe in munged mungekey slurmctld slurmd sinfo; do
    command -v "$exe" >/dev/null || { echo "local_cluster: $exe missing (apt-get install slurm-wlm munge)" >&2; exit 2; }
  done
  mkdir -p "$dir"/munge "$dir"/state "$dir"/spool
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

  read -r ctld_port slurmd_port < <(free_ports)
  local cpus mem_mb
  cpus=$(nproc)
  mem_mb=$(awk '/MemTotal/ {print int($2 / 1024 * 0.9)}' /proc/meminfo)
  cat >"$dir/slurm.conf" <<CONF
# Written by scripts/slurm/local_cluster.sh: a private single-node cluster for tests.
ClusterName=particlelab
SlurmctldHost=localhost
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
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
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
NodeName=localhost CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF=$dir/slurm.conf
  slurmctld -c -f "$SLURM_CONF"
  slurmd -f "$SLURM_CONF" -N localhost
  wait_until 60 "node localhost idle" node_idle
  echo "local_cluster: up; export SLURM_CONF=$SLURM_CONF" >&2
}

# Sends TERM to the daemon in PIDFILE, then KILL after 10 s; forgets a stale pid file.
stop_daemon() {
  local pidfile=$1 pid
  [ -s "$pidfile" ] || return 0
  pid=$(cat "$pidfile")
  if kill -0 "$pid" 2>/dev/null; then
    kill -TERM "$pid" 2>/dev/null || true
    wait_until 10 "exit of pid $pid ($pidfile)" bash -c "! kill -0 $pid" ||
      kill -KILL "$pid" 2>/dev/null || true
  fi
  rm -f "$pidfile"
}

stop() {
  if [ -f "$dir/slurm.conf" ] && [ -s "$dir/slurmctld.pid" ] && kill -0 "$(cat "$dir/slurmctld.pid")" 2>/dev/null; then
    export SLURM_CONF=$dir/slurm.conf
    # Every job of this private cluster is the test's own.
    scancel --full --quiet $(squeue -h -o %A 2>/dev/null) 2>/dev/null || true
    wait_until 20 "end of the cancelled jobs" bash -c '[ -z "$(squeue -h -o %A)" ]' || true
  fi
  stop_daemon "$dir/slurmd.pid"
  stop_daemon "$dir/slurmctld.pid"
  stop_daemon "$dir/munge/munged.pid"
}

case $action in
  start) start ;;
  stop) stop ;;
  *) usage ;;
esac
