#!/bin/bash
# A throw-away one-node Slurm cluster on 127.0.0.1 for the farm tests (recipe: ../shared/notes/slurm-local.md).
#   slurm_cluster.sh start DIR   starts munged, slurmctld and slurmd with config, spool, logs and sockets in DIR
#                                (free ports, its own munge socket: nothing outside DIR is touched), waits for
#                                the node to be idle, prints "export SLURM_CONF=DIR/slurm.conf"; exit 1 with the
#                                reason (and the daemons' log tails) when it cannot.
#   slurm_cluster.sh stop DIR    stops exactly the daemons that `start DIR` started, by the PIDs it recorded
#                                (each checked to still be that daemon of DIR), and removes the spool.
set -u
cmd=${1:?start|stop}
S=$(realpath -m "${2:?DIR}")

fail() {
  echo "slurm_cluster: cannot start the test cluster: $*" >&2
  for f in "$S"/log/*.log; do [ -f "$f" ] && { echo "--- $f" >&2; tail -n 15 "$f" >&2; }; done
  "$0" stop "$S" >/dev/null 2>&1
  exit 1
}

# Kills the process in pid file $1 if its command line mentions DIR (a recycled PID is left alone).
stop_pid() {
  local pidfile=$1 pid
  [ -f "$pidfile" ] || return 0
  pid=$(cat "$pidfile" 2>/dev/null)
  [ -n "$pid" ] && [ -r "/proc/$pid/cmdline" ] || return 0
  tr '\0' ' ' <"/proc/$pid/cmdline" | grep -qF "$S" || return 0
  kill "$pid" 2>/dev/null
  for _ in $(seq 50); do [ -d "/proc/$pid" ] || return 0; sleep 0.1; done
  kill -9 "$pid" 2>/dev/null
}

if [ "$cmd" = stop ]; then
  stop_pid "$S/d.pid"
  stop_pid "$S/ctld.pid"
  stop_pid "$S/munged.pid"
  rm -rf "$S/spool"
  exit 0
fi

[ "$cmd" = start ] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }
[ "$(id -u)" = 0 ] || fail "needs root (slurmd runs jobs as their users)"
for b in /usr/sbin/munged /usr/sbin/slurmctld /usr/sbin/slurmd sbatch sinfo; do
  command -v "$b" >/dev/null || fail "$b is not installed (setup.sh installs slurm-wlm and munge)"
done
[ -r /etc/munge/munge.key ] || fail "/etc/munge/munge.key is missing (reinstall munge)"
"$0" stop "$S" >/dev/null 2>&1
mkdir -p "$S/spool/ctld" "$S/spool/d" "$S/log" "$S/munge"
chmod 700 "$S/munge"

# munged of our own: own socket, pid, seed and log in DIR (root needs --force).
/usr/sbin/munged --force --socket="$S/munge/munge.socket" --pid-file="$S/munged.pid" \
  --key-file=/etc/munge/munge.key --log-file="$S/log/munged.log" --seed-file="$S/munge/seed" ||
  fail "munged did not start"
for _ in $(seq 50); do [ -S "$S/munge/munge.socket" ] && break; sleep 0.1; done
[ -S "$S/munge/munge.socket" ] || fail "munged made no socket"

# Free ports for slurmctld and slurmd.
read -r P1 P2 < <(python3 -c '
import socket
s=[socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')
HOST=$(hostname -s)
CPUS=$(nproc)
MEM=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2 ))
cat >"$S/slurm.conf" <<CONF
ClusterName=hfbaketest
SlurmctldHost=$HOST(127.0.0.1)
SlurmUser=root
SlurmctldPort=$P1
SlurmdPort=$P2
AuthType=auth/munge
AuthInfo=socket=$S/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$S/spool/ctld
SlurmdSpoolDir=$S/spool/d
SlurmctldPidFile=$S/ctld.pid
SlurmdPidFile=$S/d.pid
SlurmctldLogFile=$S/log/ctld.log
SlurmdLogFile=$S/log/d.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MpiDefault=none
MinJobAge=600
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=$MEM State=UNKNOWN
PartitionName=main Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$S/slurm.conf"
/usr/sbin/slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start"
/usr/sbin/slurmd -f "$SLURM_CONF" || fail "slurmd did not start"
for _ in $(seq 150); do
  state=$(sinfo -h -o %T 2>/dev/null | head -n1)
  [ "$state" = idle ] && { echo "export SLURM_CONF=$SLURM_CONF"; exit 0; }
  sleep 0.2
done
fail "the node did not become idle within 30 s (state: ${state:-none})"
