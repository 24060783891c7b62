#!/usr/bin/env bash
# Full diagnosis (every candidate of the effect library, greedy second effect, per-case trends,
# report with figures) of bundled nine-case bench sets, timed on this machine with 2 threads.
# Prints per set: wall time, the time of each candidate fit, the verdict and the share of the
# withheld gap closed. The diagnosis runs locally (thread-pool evaluators); the same diagnosis with
# its fits on a local master + 2 workers is bench/diagnose_service.sh.
# Usage: bench/diagnose_full.sh [build dir] [sets…]   (default sets: driver-lowpass creep delay nominal hinge-friction)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
shift || true
SETS=${*:-driver-lowpass creep delay nominal hinge-friction}
BIN="$BUILD/client/piezoid"
[ -x "$BIN" ] || { echo "no $BIN: build first (scripts/build.sh)" >&2; exit 2; }
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
for set in $SETS; do
  start=$(date +%s.%N)
  "$BIN" diagnose --cases "data/bimorph-fin/$set" --out "$OUT/$set" --threads 2 >"$OUT/$set.txt" 2>"$OUT/$set.err"
  end=$(date +%s.%N)
  echo "== $set: wall $(echo "$end - $start" | bc) s (load $(cut -d' ' -f1 /proc/loadavg))"
  grep -E "^  [a-z-]+: withheld RMS" "$OUT/$set.err" | sed 's/^/   /'
  grep -E "^VERDICT|share of the gap closed" "$OUT/$set.txt" | sed 's/^/   /'
done
