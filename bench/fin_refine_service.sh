#!/usr/bin/env bash
# The fin's refinement of a beam model (bimorph-fin's bench form + hinge-friction on CVODE, two
# starts, 3 Levenberg–Marquardt iterations each) by the records engine: locally on 2 threads, then
# with the polishes' residual vectors on a local master with 2 workers of 1 thread each
# (deploy/local/piezoid-local.sh, free ports, a temporary state dir). bench/bench_fin_refine.cc;
# both fits are the same bit for bit (tests/system/fin_records_service_test.cc), the walls differ.
# Usage: bench/fin_refine_service.sh [build dir]   (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
for b in "$BUILD/bench/bench_fin_refine" "$BUILD/master/piezoid-master" \
  "$BUILD/worker/piezoid-worker"; do
  [ -x "$b" ] || { echo "no $b: build first (scripts/build.sh)" >&2; exit 2; }
done
OUT=$(mktemp -d)
STATE="$OUT/state"
stop() { deploy/local/piezoid-local.sh stop --state-dir "$STATE" >/dev/null 2>&1 || true; rm -rf "$OUT"; }
trap stop EXIT
deploy/local/piezoid-local.sh start --build "$BUILD" --workers 2 --threads 1 --any-port \
  --state-dir "$STATE" --log-level warn >/dev/null
EP=$(deploy/local/piezoid-local.sh endpoint --state-dir "$STATE")
echo "master at $EP, 2 workers x 1 thread; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
PIEZOID_BENCH_MASTER="$EP" "$BUILD/bench/bench_fin_refine" --benchmark_counters_tabular=true
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
