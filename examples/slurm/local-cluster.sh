#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for tests/slurm.rs and for trying
# examples/slurm/sweep.sbatch (docs/cluster.md). Debian's slurm-wlm and munge; run as root.
#
#   examples/slurm/local-cluster.sh start    # (re)start from a fresh state; waits for an idle node
#   examples/slurm/local-cluster.sh stop     # stops what start started; removes the slurm.conf it wrote
#   examples/slurm/local-cluster.sh status   # sinfo, or exit 1 when no cluster answers
#   examples/slurm/local-cluster.sh logs     # the daemons' logs
#
# start writes /etc/slurm/slurm.conf (the path Debian's daemons and clients read; a file not
# written by this script is never replaced), one node with the CPUs and memory `slurmd -C`
# reports and one partition, SlurmUser=root, proctrack/linuxproc, task/none,
# select/cons_tres (so the array's tasks share the node's CPUs). Everything else (state,
# spool, logs, pid files) lives under $IGEMU_SLURM_STATE (default /tmp/igemu-slurm). The
# daemons talk over 127.0.0.1 (ports 6817, 6818), whatever the host name resolves to.
# munged is started as the munge user unless one already answers (then it is left alone);
# the key /etc/munge/munge.key is created when missing. No systemd is needed: the daemons
# are started directly and stopped by their pid files.
set -euo pipefail

state=${IGEMU_SLURM_STATE:-/tmp/igemu-slurm}
conf=/etc/slurm/slurm.conf
marker="# written by igemu examples/slurm/local-cluster.sh"
wait_s=${IGEMU_SLURM_START_TIMEOUT:-60}

die() {
  echo "local-cluster: error: $*" >&2
  exit 1
}

need_root() {
  [ "$(id -u)" = 0 ] || die "run as root (the daemons run as root and munged as munge)"
  local m=""
  for c in slurmctld slurmd scontrol sinfo sbatch munged munge unmunge; do
    command -v "$c" >/dev/null 2>&1 || m="$m $c"
  done
  [ -z "$m" ] || die "not installed:$m (apt-get install -y --no-install-recommends slurm-wlm munge)"
}

alive() { # pid file -> true while its process runs
  [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null
}

stop_pid() { # name, pid file: TERM, wait up to 15 s, then KILL
  local name=$1 pidf=$2 pid
  alive "$pidf" || { rm -f "$pidf"; return 0; }
  pid=$(cat "$pidf")
  kill "$pid" 2>/dev/null || true
  for _ in $(seq 1 150); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  if kill -0 "$pid" 2>/dev/null; then
    echo "local-cluster: $name ($pid) did not stop on TERM; KILL" >&2
    kill -9 "$pid" 2>/dev/null || true
  fi
  rm -f "$pidf"
  echo "local-cluster: stopped $name ($pid)"
}

munge_ok() { munge -n 2>/dev/null | unmunge >/dev/null 2>&1; }

start_munge() {
  if munge_ok; then
    echo "local-cluster: munged already answers; using it"
    return 0
  fi
  local key=/etc/munge/munge.key
  mkdir -p /etc/munge /run/munge /var/lib/munge /var/log/munge
  chown munge:munge /etc/munge /run/munge /var/lib/munge /var/log/munge
  chmod 0700 /etc/munge
  chmod 0755 /run/munge
  if [ ! -s "$key" ]; then
    if command -v mungekey >/dev/null 2>&1; then
      mungekey --create --keyfile="$key"
    else
      dd if=/dev/urandom of="$key" bs=1 count=1024 status=none
    fi
    echo "local-cluster: created $key"
  fi
  chown munge:munge "$key"
  chmod 0400 "$key"
  # Its pid and log in a folder of the munge user (munged refuses to write elsewhere).
  mkdir -p "$state/munge"
  chown munge:munge "$state/munge"
  runuser -u munge -- munged --pid-file="$state/munge/munged.pid" --log-file="$state/munge/munged.log"
  for _ in $(seq 1 50); do
    munge_ok && return 0
    sleep 0.1
  done
  cat "$state/munge/munged.log" >&2 2>/dev/null || true
  die "munged does not answer (log above)"
}

write_conf() {
  if [ -e "$conf" ] && ! grep -qxF "$marker" "$conf"; then
    die "$conf exists and was not written by this script; not replacing it (a real cluster?)"
  fi
  local node host
  # `slurmd -C` prints the node line of this machine (CPUs, sockets, cores, memory).
  node=$(slurmd -C | head -n 1)
  case "$node" in
    NodeName=*) ;;
    *) die "slurmd -C printed no node line: $node" ;;
  esac
  host=$(hostname -s)
  mkdir -p "$(dirname "$conf")"
  cat >"$conf.tmp" <<EOF
$marker
# A single-node cluster for tests; '$0 stop' removes this file.
ClusterName=igemu
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
SlurmctldPort=6817
SlurmdPort=6818
StateSaveLocation=$state/slurmctld
SlurmdSpoolDir=$state/slurmd
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
MinJobAge=600
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
  mv "$conf.tmp" "$conf"
}

logs() {
  local f
  for f in slurmctld.log slurmd.log munge/munged.log; do
    if [ -s "$state/$f" ]; then
      echo "----- $state/$f (last 60 lines)"
      tail -n 60 "$state/$f"
    fi
  done
}

stop() {
  need_root
  stop_pid slurmd "$state/slurmd.pid"
  stop_pid slurmctld "$state/slurmctld.pid"
  stop_pid munged "$state/munge/munged.pid"
  if [ -e "$conf" ] && grep -qxF "$marker" "$conf"; then
    rm -f "$conf"
  fi
}

start() {
  need_root
  stop >/dev/null
  rm -rf "$state"
  mkdir -p "$state/slurmctld" "$state/slurmd"
  start_munge
  write_conf
  # -c: no state from an earlier run; -i: ignore unreadable state.
  slurmctld -c -i || { logs >&2; die "slurmctld did not start (log above)"; }
  slurmd || { logs >&2; die "slurmd did not start (log above)"; }
  for _ in $(seq 1 $((wait_s * 2))); do
    if scontrol ping 2>/dev/null | grep -q UP && sinfo -h -o %T 2>/dev/null | grep -qx idle; then
      echo "local-cluster: up ($(sinfo -h -o '%P %D node %N %c CPUs %m MB %T'), state $state)"
      return 0
    fi
    sleep 0.5
  done
  sinfo -N -l >&2 || true
  logs >&2
  die "no idle node after ${wait_s} s (logs above)"
}

case "${1:-}" in
  start) start ;;
  stop) stop ;;
  status) sinfo -N -l && scontrol ping ;;
  logs) logs ;;
  *)
    echo "usage: $0 start|stop|status|logs" >&2
    exit 2
    ;;
esac
