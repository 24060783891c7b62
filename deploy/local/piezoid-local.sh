#!/usr/bin/env bash
# Local launcher: one piezoid-master and N piezoid-workers on 127.0.0.1.
#   deploy/local/piezoid-local.sh start  [--workers N] [--threads T] [--state-dir DIR] [--build DIR]
#                                        [--worker-port P] [--client-port P] [--any-port] [--log-level L]
#   deploy/local/piezoid-local.sh stop     [--state-dir DIR]
#   deploy/local/piezoid-local.sh status   [--state-dir DIR]
#   deploy/local/piezoid-local.sh endpoint [--state-dir DIR]   # prints the clients' endpoint
# start returns once the master has bound its endpoints (bounded wait; on failure it prints the
# master's log and stops what it started). --any-port lets the master pick free ports (see
# `endpoint`). Pids, endpoints and logs go to <state-dir>/run/; the default state dir is
# <build>/piezoid-state. stop sends SIGTERM (workers say DISCONNECT; the master keeps every job's
# checkpoint and resumes the unfinished ones on the next start), then SIGKILL after 10 s.
# Clients: build/client/piezoid submit|watch|fetch … --master "$(deploy/local/piezoid-local.sh endpoint)".
set -euo pipefail
cmd=${1:-}; shift || true
here=$(cd "$(dirname "$0")/../.." && pwd)
build="$here/${PIEZOID_BUILD_DIR:-build}"
workers=2; threads=$(nproc); state=""; wport=5555; cport=5556; any=0; level=info
while [[ $# -gt 0 ]]; do
  case $1 in
    --workers) workers=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --state-dir) state=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --worker-port) wport=$2; shift 2 ;;
    --client-port) cport=$2; shift 2 ;;
    --any-port) any=1; shift ;;
    --log-level) level=$2; shift 2 ;;
    *) echo "piezoid-local: unknown option $1" >&2; exit 2 ;;
  esac
done
[[ -n $state ]] || state="$build/piezoid-state"
run="$state/run"

alive() { [[ -f $1 ]] && kill -0 "$(cat "$1")" 2>/dev/null; }

stop_all() {
  local f pid
  for f in "$run"/worker-*.pid "$run"/master.pid; do
    [[ -f $f ]] || continue
    pid=$(cat "$f")
    kill -TERM "$pid" 2>/dev/null || true
    for _ in $(seq 1 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$pid" 2>/dev/null && kill -KILL "$pid" 2>/dev/null || true
    rm -f "$f"
  done
  rm -f "$run/endpoints"
}

case $cmd in
  start)
    for exe in "$build/master/piezoid-master" "$build/worker/piezoid-worker"; do
      [[ -x $exe ]] || { echo "piezoid-local: $exe not found: build first (scripts/build.sh)" >&2; exit 1; }
    done
    if alive "$run/master.pid"; then
      echo "piezoid-local: a master is already running from $state (pid $(cat "$run/master.pid")): stop it first" >&2
      exit 1
    fi
    mkdir -p "$run"
    rm -f "$run/endpoints"
    if ((any)); then wep="tcp://127.0.0.1:*"; cep="tcp://127.0.0.1:*"
    else wep="tcp://127.0.0.1:$wport"; cep="tcp://127.0.0.1:$cport"; fi
    "$build/master/piezoid-master" --workers "$wep" --clients "$cep" --state-dir "$state" \
      --endpoints-file "$run/endpoints" --log-level "$level" >>"$run/master.log" 2>&1 &
    echo $! >"$run/master.pid"
    for _ in $(seq 1 100); do
      [[ -s $run/endpoints ]] && break
      if ! alive "$run/master.pid"; then break; fi
      sleep 0.1
    done
    if [[ ! -s $run/endpoints ]]; then
      echo "piezoid-local: the master did not start; the end of $run/master.log:" >&2
      tail -n 20 "$run/master.log" >&2 || true
      stop_all
      exit 1
    fi
    wep=$(sed -n 1p "$run/endpoints"); cep=$(sed -n 2p "$run/endpoints")
    for ((i = 0; i < workers; i++)); do
      "$build/worker/piezoid-worker" --master "$wep" --threads "$threads" --log-level "$level" \
        >>"$run/worker-$i.log" 2>&1 &
      echo $! >"$run/worker-$i.pid"
    done
    echo "piezoid-local: master pid $(cat "$run/master.pid"): workers $wep, clients $cep;" \
         "$workers workers x $threads threads; state and logs in $state"
    ;;
  stop) stop_all ;;
  status)
    for f in "$run"/*.pid; do
      [[ -f $f ]] || continue
      pid=$(cat "$f"); if kill -0 "$pid" 2>/dev/null; then s=running; else s=gone; fi
      echo "$(basename "$f" .pid) $pid $s"
    done
    [[ -s $run/endpoints ]] && echo "clients $(sed -n 2p "$run/endpoints")"
    ;;
  endpoint)
    [[ -s $run/endpoints ]] || { echo "piezoid-local: no master started from $state" >&2; exit 1; }
    sed -n 2p "$run/endpoints"
    ;;
  *) sed -n 2,13p "$0"; exit 2 ;;
esac
