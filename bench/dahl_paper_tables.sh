#!/usr/bin/env bash
# Dahl networks at paper scale: `piezoid dahl` on the four cases, LM (trainlm) and BR (trainbr), 100
# tansig neurons, 70/15/15 split, then our MSE per subset and time beside the paper's Tables 3 and 4.
# Usage: bench/dahl_paper_tables.sh [build dir] [seed] [extra `piezoid dahl` flags…]
# min_grad is tested in normalised target units unless `--min-grad-units target` is passed (MATLAB's
# literal test; see docs/performance.md, "Studies against published figures").
# Writes the JSON / CSV summaries and per-run epoch histories to $OUT (default: a temporary folder,
# kept and printed at the end).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
SEED=${2:-1}
shift $(( $# > 2 ? 2 : $# )) || true
BIN="$BUILD/client/piezoid"
[ -x "$BIN" ] || { echo "no $BIN: build first (scripts/build.sh)" >&2; exit 2; }
OUT=${OUT:-$(mktemp -d)}
mkdir -p "$OUT"
echo "== piezoid dahl --seed $SEED $* (uptime: $(uptime | sed 's/.*load/load/'))"
"$BIN" dahl --seed "$SEED" --json "$OUT/dahl.json" --csv "$OUT/dahl.csv" --history-dir "$OUT/history" "$@" \
  | tee "$OUT/dahl.log"
echo "== summaries in $OUT"
