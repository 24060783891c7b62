#!/usr/bin/env bash
# Resident memory (VmRSS from /proc/PID/status) of the service processes: an idle piezoid-master,
# an idle piezoid-worker, then the master holding N running hgann jobs (default 10 copies of
# examples/hgann_job.json: 9 bench cases, population 400 × 1415 bits each) and the worker serving
# them. Uses deploy/local/piezoid-local.sh on free ports with a temporary state directory; stops
# everything it started on exit. Figures go to docs/performance.md.
#   bench/memory.sh [jobs] [job.json]        (PIEZOID_BUILD_DIR selects the build, default build)
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${1:-10}
SPEC=${2:-examples/hgann_job.json}
BUILD="${PIEZOID_BUILD_DIR:-build}"
BIN="$BUILD/client/piezoid"
STATE=$(mktemp -d "${TMPDIR:-/tmp}/pz-memory.XXXXXX")
LAUNCH=(deploy/local/piezoid-local.sh)
cleanup() { "${LAUNCH[@]}" stop --state-dir "$STATE" --build "$BUILD" >/dev/null 2>&1 || true; rm -rf "$STATE"; }
trap cleanup EXIT

rss() { awk '/^VmRSS:/ { printf "%.1f MB", $2 / 1024 }' "/proc/$1/status"; }

"${LAUNCH[@]}" start --workers 1 --threads 1 --any-port --state-dir "$STATE" --build "$BUILD" --log-level warn >/dev/null
EP=$("${LAUNCH[@]}" endpoint --state-dir "$STATE" --build "$BUILD")
MASTER=$(cat "$STATE/run/master.pid")
WORKER=$(cat "$STATE/run/worker-0.pid")
for _ in $(seq 1 50); do "$BIN" list --master "$EP" 2>/dev/null | grep -q "^1 worker" && break; sleep 0.1; done
sleep 1
echo "idle master:  $(rss "$MASTER")"
echo "idle worker:  $(rss "$WORKER")"

ids=()
for _ in $(seq 1 "$JOBS"); do ids+=("$("$BIN" submit "$SPEC" --master "$EP")"); done
sleep 5  # every job has drawn and started evaluating its population
echo "master holding $JOBS running jobs ($SPEC): $(rss "$MASTER")"
echo "worker serving them (1 thread, job contexts cached): $(rss "$WORKER")"
"$BIN" list --master "$EP" | head -n 1
for id in "${ids[@]}"; do "$BIN" cancel "$id" --master "$EP" >/dev/null; done
