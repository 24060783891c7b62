#!/usr/bin/env bash
# `piezoid fit --family auto` on a record set against the grid fitted by hand (issue 45: auto within
# 1.1x of the best of the grid on sets it was not tuned on). Runs auto (CPU and wall time), then
# every candidate of its grid as an ordinary `piezoid fit` on the training records, and prints each
# one's withheld RMSE, the best, and auto's ratio to it.
#
# Usage: bench/auto_vs_grid.sh [build dir] RECORD_SET [extra `piezoid fit` flags…]
#   e.g. bench/auto_vs_grid.sh build data/yan9a-p885-stack
#   a real-like set: piezoid synth-stack --ringing --out /tmp/ring --seed 3
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
SET=${2:?record set}
shift 2
BIN="$BUILD/client/piezoid"
[ -x "$BIN" ] || { echo "no $BIN: build first (scripts/build.sh)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "no /usr/bin/time (Debian: apt-get install time)" >&2; exit 2; }
OUT=${OUT:-$(mktemp -d)}
withheld() {
  python3 - "$1" <<'PY'
import json, math, sys
r = json.load(open(sys.argv[1]))["records"]
sse = sum(x["rmse"] ** 2 * x["samples"] for x in r if x["role"] != "train" and x.get("rmse") is not None)
n = sum(x["samples"] for x in r if x["role"] != "train")
print(f"{math.sqrt(sse / n):.4g}" if n else "nan")
PY
}
echo "== $SET: fit --family auto (nproc $(nproc), load $(cut -d' ' -f1 /proc/loadavg))"
/usr/bin/time -f "time: wall %e s, CPU %U + %S s" "$BIN" fit --records "$SET" --family auto \
  --out "$OUT/auto" --no-figures --quiet "$@" 2>&1 | grep -v "^  initial state, \(validate\|test\)"
AUTO=$(withheld "$OUT/auto/fit.json")
echo "auto: withheld RMSE $AUTO"
echo "== the grid by hand (each candidate fitted on the training records)"
python3 - "$OUT/auto/fit.json" <<'PY' | sort -u > "$OUT/grid.txt"
import json, sys
s = json.load(open(sys.argv[1]))["selection"]
for c in s["ranking"]:
    print(c["family"], c.get("levels") or 12, ",".join(c.get("effects", [])) or "none",
          c["initial_state"])
PY
BEST=inf
while read -r fam lev eff st; do
  flags=(--records "$SET" --family "$fam" --pi-operators "$lev" --out "$OUT/grid" --no-figures --quiet)
  [ "$eff" != none ] && flags+=(--effects "$eff")
  case "$fam" in duhem|bw-oscillator) ;; *) [ "$st" != auto ] && flags+=(--initial-state "$st") ;; esac
  if "$BIN" fit "${flags[@]}" "$@" >/dev/null 2>"$OUT/grid.err"; then
    W=$(withheld "$OUT/grid/fit.json")
  else
    W="failed: $(head -c 120 "$OUT/grid.err")"
  fi
  echo "  $fam $lev $eff $st: withheld RMSE $W"
  BEST=$(python3 -c "import math,sys; a,b=sys.argv[1],sys.argv[2]
try: print(min(float(a), float(b)))
except ValueError: print(a)" "$BEST" "$W")
done < "$OUT/grid.txt"
python3 -c "import sys; a,b=float(sys.argv[1]),float(sys.argv[2]); print(f'best of the grid {b:.4g}; auto {a:.4g} = {a/b:.3g} x the best')" "$AUTO" "$BEST"
echo "report: $OUT/auto/report.md"
