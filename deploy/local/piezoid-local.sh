#!/usr/bin/env bash
# Local launcher: one piezoid-master and N piezoid-workers on 127.0.0.1.
#   deploy/local/piezoid-local.sh start [--workers N] [--threads T] [--state-dir DIR] [--build DIR]
#                                       [--worker-port P] [--client-port P]
#   deploy/local/piezoid-local.sh stop  [--state-dir DIR]
#   deploy/local/piezoid-local.sh status [--state-dir DIR]
# Pids and logs go to <state-dir>/run/. Stop sends SIGTERM (workers say DISCONNECT; the master
# keeps every job's checkpoint and resumes them on the next start).
set -euo pipefail
cmd=${1:-}; shift || true
here=$(cd "$(dirname "$0")/../.." && pwd)
workers=2; threads=$(nproc); state="$here/piezoid-state"; build="$here/${PIEZOID_BUILD_DIR:-build}"
wport=5555; cport=5556
while [[ $# -gt 0 ]]; do
  case $1 in
    --workers) workers=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --state-dir) state=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --worker-port) wport=$2; shift 2 ;;
    --client-port) cport=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
run="$state/run"
case $cmd in
  start)
    mkdir -p "$run"
    "$build/master/piezoid-master" --workers "tcp://127.0.0.1:$wport" --clients "tcp://127.0.0.1:$cport" \
      --state-dir "$state" >>"$run/master.log" 2>&1 &
    echo $! >"$run/master.pid"
    for ((i = 0; i < workers; i++)); do
      "$build/worker/piezoid-worker" --master "tcp://127.0.0.1:$wport" --threads "$threads" \
        >>"$run/worker-$i.log" 2>&1 &
      echo $! >"$run/worker-$i.pid"
    done
    echo "master: workers tcp://127.0.0.1:$wport, clients tcp://127.0.0.1:$cport; $workers workers × $threads threads; logs in $run"
    ;;
  stop)
    for f in "$run"/worker-*.pid "$run"/master.pid; do
      [[ -f $f ]] || continue
      pid=$(cat "$f")
      kill -TERM "$pid" 2>/dev/null || true
      for _ in $(seq 1 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
      kill -0 "$pid" 2>/dev/null && kill -KILL "$pid" 2>/dev/null || true
      rm -f "$f"
    done
    ;;
  status)
    for f in "$run"/*.pid; do
      [[ -f $f ]] || continue
      pid=$(cat "$f"); if kill -0 "$pid" 2>/dev/null; then s=running; else s=gone; fi
      echo "$(basename "$f" .pid) $pid $s"
    done
    ;;
  *) sed -n 2,8p "$0"; exit 2 ;;
esac
