#!/usr/bin/env bash
# Full Bouc–Wen benchmark identification (piezoid boucwen) per algorithm: wall time, evaluations,
# evaluations/s, time and evaluations to reach the final criterion (within 1 % of the final training
# cost), training RMS and the simulation RMS errors on the official test sets (from report.json).
# Usage: bench/boucwen_identify.sh [build dir] [algorithms…]   (default: pso ga-real ga-binary)
# Extra flags via BOUCWEN_FLAGS (default: --repetitions 2 --train-periods 2 --iterations 1000
# --stall 100 --threads 2). Reports are kept in $OUT (default: a temporary folder, removed).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
shift || true
ALGORITHMS=${*:-pso ga-real ga-binary}
BIN="$BUILD/client/piezoid"
[ -x "$BIN" ] || { echo "no $BIN: build first (scripts/build.sh)" >&2; exit 2; }
FLAGS=${BOUCWEN_FLAGS:---repetitions 2 --train-periods 2 --iterations 1000 --stall 100 --threads 2}
if [ -z "${OUT:-}" ]; then
  OUT=$(mktemp -d)
  trap 'rm -rf "$OUT"' EXIT
fi
mkdir -p "$OUT"
field() { grep -o "\"$1\": [^,}]*" "$2" | head -1 | sed 's/.*: //'; }
for alg in $ALGORITHMS; do
  start=$(date +%s.%N)
  # shellcheck disable=SC2086
  "$BIN" boucwen --algorithm "$alg" --out "$OUT/$alg" --no-plots --progress 0 $FLAGS >"$OUT/$alg.log" 2>&1
  end=$(date +%s.%N)
  r="$OUT/$alg/report.json"
  echo "== $alg  flags '$FLAGS'  wall $(echo "$end - $start" | bc) s (search $(field wall_time_s "$r") s)"
  echo "   evaluations $(field evaluations "$r"), $(field evaluations_per_s "$r") /s;" \
       "within 1 % of the final cost after $(field evaluations_to_final "$r") evaluations, $(field seconds_to_final "$r") s"
  echo "   training RMS $(field training_rms_m "$r") m; test RMS multisine $(field test_multisine_rms_m "$r") m," \
       "sine sweep $(field test_sinesweep_rms_m "$r") m (true model $(field true_model_multisine_rms_m "$r")," \
       "$(field true_model_sinesweep_rms_m "$r") m)"
  grep -E "^  (m|c|k|alpha|beta_gamma|beta_delta) =" "$OUT/$alg.log" | sed 's/^/  /'
done
