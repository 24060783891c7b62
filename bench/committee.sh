#!/usr/bin/env bash
# Committee machine at full scale (seed 002): `piezoid committee` on the bundled
# data/piezo-stack-bench — 2 families x 2 optimisers (PSO, real GA), complete + 4 bands, 5
# repetitions each — then the timing table of its report (evaluations/s, wall time per band).
# Usage: bench/committee.sh [build dir] [threads] [extra `piezoid committee` flags…]
# Writes report.md, committee.json and the figures to $OUT (default: a temporary folder, kept and
# printed at the end).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
THREADS=${2:-2}
shift $(( $# > 2 ? 2 : $# )) || true
BIN="$BUILD/client/piezoid"
[ -x "$BIN" ] || { echo "no $BIN: build first (scripts/build.sh)" >&2; exit 2; }
OUT=${OUT:-$(mktemp -d)}
mkdir -p "$OUT"
echo "== piezoid committee --threads $THREADS $* (nproc $(nproc), $(uptime | sed 's/.*load/load/'))"
/usr/bin/time -f "== wall %e s, user %U s, max RSS %M kB" \
  "$BIN" committee --threads "$THREADS" --out "$OUT" "$@" | tee "$OUT/committee.log"
echo "== timing (from $OUT/report.md)"
sed -n '/^## Timing/,$p' "$OUT/report.md"
echo "== report, committee.json and figures in $OUT"
