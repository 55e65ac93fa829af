#!/usr/bin/env bash
# Stop the one-node Slurm cluster started by .ci/slurm-up.sh (slurmd, slurmctld,
# munged), using their pid files. Safe to run when nothing is running.
# Jobs still running are not cancelled: run `scancel --user=$USER` first if
# you want them gone (slurmstepd processes outlive slurmd otherwise).
set -euo pipefail

log() { echo "[slurm-down] $*"; }

if [[ $(id -u) -ne 0 ]]; then
  echo "[slurm-down] ERROR: must run as root" >&2
  exit 1
fi

stop_pidfile() {
  local pidfile=$1 name=$2 pid i
  if [[ -s $pidfile ]]; then
    pid=$(cat "$pidfile" 2>/dev/null || true)
    if [[ $pid =~ ^[0-9]+$ && $(cat "/proc/$pid/comm" 2>/dev/null || true) == "$name" ]]; then
      log "stopping $name (pid $pid)"
      kill -TERM "$pid" 2>/dev/null || true
      for ((i = 0; i < 150; i++)); do
        [[ -d /proc/$pid ]] || break
        sleep 0.1
      done
      if [[ -d /proc/$pid ]]; then
        log "$name did not exit after 15 s, sending SIGKILL"
        kill -KILL "$pid" 2>/dev/null || true
      fi
    else
      log "$name not running (stale pid file)"
    fi
    rm -f "$pidfile"
  else
    log "$name not running"
  fi
}

stop_pidfile /run/slurmd.pid slurmd
stop_pidfile /run/slurmctld.pid slurmctld
stop_pidfile /run/munge/munged.pid munged
