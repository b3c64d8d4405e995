#!/usr/bin/env bash
# A private single-node Slurm (munge, slurmctld, slurmd from Debian's munge and slurm-wlm) for the farm-executor
# test. Needs root. Everything it writes (key, sockets, state, spool, logs, pid files) stays under DIR, and its
# two TCP ports are picked free, so it runs beside a system Slurm or another copy of itself.
#   scripts/slurm_local.sh start DIR   start the daemons; prints the slurm.conf to export as SLURM_CONF
#   scripts/slurm_local.sh stop DIR    stop them by their pid files
# The scheduler runs every second (sched/builtin, sched_interval=1): a job that waits on --dependency=afterok
# starts about a second after its dependency ends, instead of the default cycle of tens of seconds.
set -euo pipefail

usage() { echo "usage: $0 start|stop DIR" >&2; exit 2; }
[ $# -eq 2 ] || usage
dir=$(realpath -m "$2")

free_port() {
  for port in $(shuf -i 20000-60000 -n 100); do
    if ! ss -Hltn "sport = :$port" | grep -q .; then echo "$port"; return; fi
  done
  echo "no free TCP port found" >&2; exit 1
}

stop_daemons() { # NAME...: SIGTERM to all at once (each takes a second or two to exit), then wait
  local pids=()
  local name pid
  for name in "$@"; do
    pid=$(cat "$dir/$name.pid" 2>/dev/null) || continue
    if kill "$pid" 2>/dev/null; then pids+=("$pid"); fi
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || continue 2; sleep 0.1; done
    echo "pid $pid ignored SIGTERM; killing it" >&2
    kill -9 "$pid" 2>/dev/null || true
  done
}

case "$1" in
start)
  [ "$(id -u)" -eq 0 ] || { echo "$0: a private Slurm needs root" >&2; exit 1; }
  for tool in munged slurmctld slurmd sinfo; do
    command -v "$tool" >/dev/null || { echo "$0: $tool is missing (apt-get install munge slurm-wlm)" >&2; exit 1; }
  done
  mkdir -p "$dir/state" "$dir/spool"
  chmod 700 "$dir"
  host=$(hostname -s)

  head -c 1024 /dev/urandom > "$dir/munge.key"
  chmod 400 "$dir/munge.key"
  # --force: munged refuses to run as root without it.
  munged --force --socket="$dir/munge.socket" --key-file="$dir/munge.key" --log-file="$dir/munged.log" \
    --pid-file="$dir/munged.pid" --seed-file="$dir/munged.seed"

  cat > "$dir/slurm.conf" <<EOF
ClusterName=prt-test
SlurmctldHost=$host
SlurmUser=root
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
ReturnToService=2
MpiDefault=none
MailProg=/bin/true
SchedulerType=sched/builtin
SchedulerParameters=sched_interval=1
MinJobAge=600
NodeName=$host CPUs=$(nproc) RealMemory=1000 State=UNKNOWN
PartitionName=prt Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF="$dir/slurm.conf"
  slurmctld -f "$SLURM_CONF"
  slurmd -f "$SLURM_CONF"
  for _ in $(seq 100); do
    if [ "$(sinfo --noheader --format=%t 2>/dev/null)" = "idle" ]; then echo "$SLURM_CONF"; exit 0; fi
    sleep 0.2
  done
  echo "$0: the node did not come up; see $dir/slurmctld.log and $dir/slurmd.log" >&2
  exit 1
  ;;
stop)
  stop_daemons slurmd slurmctld munged
  ;;
*) usage ;;
esac
