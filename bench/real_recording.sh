#!/usr/bin/env bash
# Out-of-sample figures of every plant family on a real recording (issue 14): `piezoid fit` on the
# training window, the withheld window scored, then `piezoid diagnose --records` on one family.
# The recording is not in the project (the 150 V / 1 Hz actuator record has no licence): give its
# path. Any single CSV with a header works (time, drive, response with units, see docs/records.md).
#
# Usage: bench/real_recording.sh RECORD.csv [build dir] [train START:END] [validate START:END]
#   e.g. bench/real_recording.sh ~/data/piezo_150V_1Hz.csv build 4:7 7:10
# Env: FAMILIES (default: all eight), DIAGNOSE_FAMILY (default stack-bouc-wen; empty = none),
#      OUT (default: a temporary folder, kept and printed), FIT_FLAGS (extra `piezoid fit` flags).
set -euo pipefail
cd "$(dirname "$0")/.."
REC=${1:?usage: bench/real_recording.sh RECORD.csv [build dir] [train START:END] [validate START:END]}
BUILD=${2:-build}
TRAIN=${3:-4:7}
VALIDATE=${4:-7:10}
BIN="$BUILD/client/piezoid"
[ -x "$BIN" ] || { echo "no $BIN: build first (scripts/build.sh)" >&2; exit 2; }
[ -f "$REC" ] || { echo "no file $REC" >&2; exit 2; }
FAMILIES=${FAMILIES:-stack-bouc-wen backlash-like duhem prandtl-ishlinskii bw-oscillator bimorph-fin preisach asymmetric-pi}
DIAGNOSE_FAMILY=${DIAGNOSE_FAMILY-stack-bouc-wen}
OUT=${OUT:-$(mktemp -d)}
mkdir -p "$OUT"
echo "== $(basename "$REC"): train $TRAIN s, validate $VALIDATE s (nproc $(nproc))"
printf '| family | parameters | train RMSE | validate RMSE | validate max | validate NRMSE | wall [s] |\n'
printf '|---|---|---|---|---|---|---|\n'
for f in $FAMILIES; do
  start=$(date +%s.%N)
  # shellcheck disable=SC2086
  "$BIN" fit --records "$REC" --family "$f" --train-window "$TRAIN" --validate-window "$VALIDATE" \
    --out "$OUT/$f" --no-figures --quiet ${FIT_FLAGS:-} > "$OUT/$f.log" 2>&1 || { echo "| $f | failed: see $OUT/$f.log |"; continue; }
  end=$(date +%s.%N)
  python3 - "$OUT/$f/fit.json" "$f" "$start" "$end" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
u = d.get("response_unit", "")
rec = {r["role"]: r for r in d["records"]}
t, v = rec["train"], rec["validate"]
n = len(d.get("params", {})) + len(d.get("weights", []) or [])
print(f"| {sys.argv[2]} | {n} | {t['rmse']:.4f} {u} | {v['rmse']:.4f} {u} | {v['max_abs']:.3f} {u} | "
      f"{v['nrmse_pct']:.3f} % | {float(sys.argv[4]) - float(sys.argv[3]):.1f} |")
PY
done
if [ -n "$DIAGNOSE_FAMILY" ]; then
  echo "== piezoid diagnose --records on $DIAGNOSE_FAMILY"
  "$BIN" diagnose --records "$REC" --family "$DIAGNOSE_FAMILY" --train-window "$TRAIN" \
    --validate-window "$VALIDATE" --out "$OUT/diagnose-$DIAGNOSE_FAMILY" > "$OUT/diagnose.log" 2>&1 \
    || { echo "diagnose failed: see $OUT/diagnose.log"; exit 1; }
  # The verdict, the noise floor and the candidates (the report up to the named model).
  sed -n '3,/^## The named model/p' "$OUT/diagnose-$DIAGNOSE_FAMILY/report.md" | grep -v '^## The named model'
fi
echo "== fits, logs and the diagnosis in $OUT"
