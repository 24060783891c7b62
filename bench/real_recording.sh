#!/usr/bin/env bash
# Out-of-sample figures of every plant family on a real recording (issue 14): `piezoid fit` on the
# training window, the withheld window scored, then `piezoid diagnose --records` on one family.
# The recording is not in the project (the 150 V / 1 Hz actuator record has no licence): give its
# path. Any single CSV with a header works (time, drive, response with units, see docs/records.md).
#
# Usage: bench/real_recording.sh RECORD.csv [build dir] [train START:END] [validate START:END]
#   e.g. bench/real_recording.sh ~/data/piezo_150V_1Hz.csv build 4:7 7:10
# Env: FAMILIES (default: all eight), EFFECTS (effect sets, space-separated, `none` = the family
#      alone; default "none"; e.g. EFFECTS="none delay creep creep-spectrum,delay"),
#      DIAGNOSE_FAMILY (default stack-bouc-wen; empty = none),
#      OUT (default: a temporary folder, kept and printed), FIT_FLAGS (extra `piezoid fit` flags).
# CPU is the fit's user + system time (/usr/bin/time): on a loaded machine quote it, not the wall.
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
EFFECTS=${EFFECTS:-none}
[ -x /usr/bin/time ] || { echo "no /usr/bin/time (Debian: apt-get install time)" >&2; exit 2; }
DIAGNOSE_FAMILY=${DIAGNOSE_FAMILY-stack-bouc-wen}
OUT=${OUT:-$(mktemp -d)}
mkdir -p "$OUT"
echo "== $(basename "$REC"): train $TRAIN s, validate $VALIDATE s (nproc $(nproc))"
printf '| family | effects | parameters | train RMSE | validate RMSE | validate max | validate NRMSE | evaluations | CPU [s] | wall [s] | search |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|\n'
for f in $FAMILIES; do
  for e in $EFFECTS; do
    name=$f; eff=()
    if [ "$e" != none ]; then name="$f+${e//,/+}"; eff=(--effects "$e"); fi
    # shellcheck disable=SC2086
    /usr/bin/time -f "%U %S %e" -o "$OUT/$name.time" "$BIN" fit --records "$REC" --family "$f" "${eff[@]}" \
      --train-window "$TRAIN" --validate-window "$VALIDATE" --out "$OUT/$name" --no-figures --quiet ${FIT_FLAGS:-} \
      > "$OUT/$name.log" 2>&1 || { echo "| $f | $e | failed: see $OUT/$name.log |"; continue; }
    python3 - "$OUT/$name/fit.json" "$f" "$e" "$OUT/$name.time" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
user, system, wall = map(float, open(sys.argv[4]).read().split())
m = d["model"]  # fit.json version 2: the model written once
u = m.get("response_unit", "")
rec = {r["role"]: r for r in d["records"]}
t, v = rec["train"], rec["validate"]
n = len(m.get("params", [])) + len(m.get("weights", []) or [])
s = d.get("search", {})
print(f"| {sys.argv[2]} | {sys.argv[3]} | {n} | {t['rmse']:.4f} {u} | {v['rmse']:.4f} {u} | {v['max_abs']:.3f} {u} | "
      f"{v['nrmse_pct']:.3f} % | {int(d['evaluations'])} | {user + system:.1f} | {wall:.1f} | {s.get('summary', '')} |")
PY
  done
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
