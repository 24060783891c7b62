#!/usr/bin/env bash
# Full diagnosis (every candidate of the effect library, greedy second effect, per-case trends,
# report) of one bundled nine-case bench with every fit's evaluations on the service: a local
# master and 2 workers of 1 thread each (deploy/local/piezoid-local.sh, free ports, a temporary
# state dir), `piezoid diagnose --master`; then the same diagnosis locally (--threads 2), and a check
# that both diagnosis.json files are identical but for the wall times.
# Usage: bench/diagnose_service.sh [build dir] [set]   (default: build, driver-lowpass)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
SET=${2:-driver-lowpass}
BIN="$BUILD/client/piezoid"
for b in "$BIN" "$BUILD/master/piezoid-master" "$BUILD/worker/piezoid-worker"; do
  [ -x "$b" ] || { echo "no $b: build first (scripts/build.sh)" >&2; exit 2; }
done
OUT=$(mktemp -d)
STATE="$OUT/state"
stop() { deploy/local/piezoid-local.sh stop --state-dir "$STATE" >/dev/null 2>&1 || true; rm -rf "$OUT"; }
trap stop EXIT
deploy/local/piezoid-local.sh start --build "$BUILD" --workers 2 --threads 1 --any-port --state-dir "$STATE" \
  --log-level warn >/dev/null
EP=$(deploy/local/piezoid-local.sh endpoint --state-dir "$STATE")
echo "master at $EP, 2 workers x 1 thread; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
start=$(date +%s.%N)
"$BIN" diagnose --cases "data/bimorph-fin/$SET" --out "$OUT/service" --master "$EP" --no-plots \
  >"$OUT/service.txt" 2>"$OUT/service.err"
end=$(date +%s.%N)
echo "== $SET on the service: wall $(echo "$end - $start" | bc) s (load $(cut -d' ' -f1 /proc/loadavg))"
grep -E "^  [a-z-]+: training RMS" "$OUT/service.err" | sed 's/^/   /' || true
grep -E "^VERDICT|share of the gap closed" "$OUT/service.txt" | sed 's/^/   /'
"$BIN" list --master "$EP" | tail -n 3 | sed 's/^/   /'
start=$(date +%s.%N)
"$BIN" diagnose --cases "data/bimorph-fin/$SET" --out "$OUT/local" --threads 2 --no-plots \
  >"$OUT/local.txt" 2>"$OUT/local.err"
end=$(date +%s.%N)
echo "== $SET locally (2 threads): wall $(echo "$end - $start" | bc) s"
strip() { sed -E 's/"wall_time_s": [-+0-9.eE]+/"wall_time_s": _/g' "$1"; }
if diff <(strip "$OUT/service/diagnosis.json") <(strip "$OUT/local/diagnosis.json") >/dev/null; then
  echo "diagnosis.json: identical on the service and locally (but for wall times)"
else
  echo "diagnosis.json: DIFFERENT on the service and locally" >&2
  diff <(strip "$OUT/service/diagnosis.json") <(strip "$OUT/local/diagnosis.json") | head -20 >&2
  exit 1
fi
