#!/usr/bin/env bash
# Paper-scale HGANN identification on this machine (population 400, up to 1000 generations, stall
# 200, threaded evaluator on all cores) on the bundled nominal bench set, for a list of seeds.
# Prints wall time, final cost and the PI of every case against the paper's Table 8.
# Usage: bench/identify_paper_scale.sh [build dir] [seeds…]   (extra identify flags via IDENTIFY_FLAGS)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
shift || true
SEEDS=${*:-1 2 3}
BIN="$BUILD/client/piezoid"
[ -x "$BIN" ] || { echo "no $BIN: build first (scripts/build.sh)" >&2; exit 2; }
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
for seed in $SEEDS; do
  start=$(date +%s.%N)
  # shellcheck disable=SC2086
  "$BIN" identify --seed "$seed" --out "$OUT/seed$seed" --no-plots ${IDENTIFY_FLAGS:-} >"$OUT/seed$seed.log" 2>&1
  end=$(date +%s.%N)
  echo "== seed $seed  flags '${IDENTIFY_FLAGS:-}'  wall $(echo "$end - $start" | bc) s"
  grep -E "^GA |best network|below the paper" "$OUT/seed$seed.log"
  sed -n '/PI per case/,/below the paper/p' "$OUT/seed$seed.log" | sed -n '2,6p'
done
