#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for `make farm-demo` and the
# farm_slurm test. Installs slurm-wlm and munge when missing, writes
# /etc/slurm/slurm.conf (never over one it did not write), starts munged,
# slurmctld and slurmd as plain daemons (containers have no systemd; no
# cgroups either, hence proctrack/linuxproc and task/none) and waits until
# the node is up. Anything that does not come up fails with the logs.
#
#   farm/cluster.sh         bring the cluster up (nothing to do when it is)
#   farm/cluster.sh status  prints the state of each daemon and of the node;
#                           succeeds when the cluster is up
#   farm/cluster.sh stop    stop the three daemons (by their pid files)
set -euo pipefail

conf=/etc/slurm/slurm.conf
marker="# written by pelage farm/cluster.sh"
logs=(/var/log/munge/munged.log /var/log/slurm/slurmctld.log /var/log/slurm/slurmd.log)
pids=(/run/slurmd.pid /run/slurmctld.pid /run/munge/munged.pid)

# What each log held before this run: a failure shows only what came after.
declare -A seen
for log in "${logs[@]}"; do seen[$log]=$( (cat "$log" 2>/dev/null || true) | wc -l); done
fail() {
  echo "cluster.sh: FAILED: $*" >&2
  for log in "${logs[@]}"; do
    if [ -f "$log" ]; then
      echo "--- $log (this run, last 40 lines but recovered jobs)" >&2
      tail -n +"$((seen[$log] + 1))" "$log" | grep -v 'Recovered JobId' | tail -n 40 >&2
    fi
  done
  exit 1
}

running() { [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

# sinfo retries for 10 s when slurmctld is down: ask only when it runs.
up() {
  running /run/slurmctld.pid && running /run/slurmd.pid &&
    [[ $(sinfo -h -N -o %t 2>/dev/null) =~ ^(idle|mix|alloc)$ ]]
}
# One line: the node's state as slurmctld sees it and each daemon running
# (with its pid) or not; the exit status says whether the cluster is up.
status() {
  local names=(slurmd slurmctld munged) daemons="" node="unknown (slurmctld not running)" i
  for i in "${!pids[@]}"; do
    if running "${pids[$i]}"; then
      daemons+="${daemons:+, }${names[$i]} running (pid $(cat "${pids[$i]}"))"
    else
      daemons+="${daemons:+, }${names[$i]} not running"
    fi
  done
  if running /run/slurmctld.pid; then
    node=$(sinfo -h -N -o '%N %t' 2>/dev/null | head -n 1 || true)
    node=${node:-"not known to slurmctld"}
  fi
  if up; then
    echo "cluster.sh: up: node $node; $daemons"
  else
    echo "cluster.sh: down: node $node; $daemons"
    return 1
  fi
}
if [ "${1:-}" = status ]; then status; exit; fi

[ "$(id -u)" = 0 ] || fail "needs root (it installs packages and starts daemons)"

if [ "${1:-}" = stop ]; then
  for pid in "${pids[@]}"; do
    if running "$pid"; then kill "$(cat "$pid")"; fi
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do running "$pid" || break; sleep 0.2; done
    ! running "$pid" || fail "$pid: the daemon did not stop"
  done
  exit 0
fi

if up; then exit 0; fi

missing=()
for p in slurm-wlm munge; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ ${#missing[@]} != 0 ]; then
  echo "cluster.sh: installing ${missing[*]}"
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
fi

if [ -f "$conf" ] && ! grep -qxF "$marker" "$conf"; then
  fail "$conf exists and was not written by this script; not touching a real cluster's configuration"
fi
host=$(hostname -s)
cat > "$conf" <<EOF
$marker
# One node, this machine, reached on 127.0.0.1.
ClusterName=pelage
SlurmctldHost=$host(127.0.0.1)
SlurmUser=slurm
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/builtin
SchedulerParameters=batch_sched_delay=0
MailProg=/bin/true
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=farm Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

# Runs daemon "$2 ..." unless the process in pid file $1 runs, and waits for
# the pid file the daemon writes once it has forked.
start() {
  local pidfile=$1
  shift
  if running "$pidfile"; then return; fi
  rm -f "$pidfile"
  "$@" || fail "$* did not start"
  for _ in $(seq 50); do if [ -s "$pidfile" ]; then return; fi; sleep 0.2; done
  fail "$*: no $pidfile after 10 s"
}

# munge: the key the package made, its run directory (a tmpfs, so made here)
[ -s /etc/munge/munge.key ] || runuser -u munge -- mungekey --create || fail "cannot create the munge key"
install -d -o munge -g munge -m 0755 /run/munge
start /run/munge/munged.pid runuser -u munge -- /usr/sbin/munged
munge -n | unmunge >/dev/null || fail "munge cannot encode and decode a credential"

install -d -o slurm -g slurm /var/spool/slurmctld /var/log/slurm
install -d /var/spool/slurmd
start /run/slurmctld.pid /usr/sbin/slurmctld
start /run/slurmd.pid /usr/sbin/slurmd

SECONDS=0
while [ "$SECONDS" -lt 60 ]; do
  for pid in "${pids[@]}"; do running "$pid" || fail "the daemon of $pid exited"; done
  if up; then
    echo "cluster.sh: node $host up ($(nproc) CPUs)"
    exit 0
  fi
  sleep 1
done
fail "node $host not up after 60 s: $(sinfo -N 2>&1 | tr '\n' ' ')"
