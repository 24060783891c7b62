#!/usr/bin/env bash
# `piezoid fit --family auto` (issue 37) on a real-like stack (synth/reallike.h): a 40 s training
# sine at 200 Hz and withheld records (a ramped sine, random reversals, a second sine), made by
# `piezoid synth-stack`; then the chosen model, its CV RMSE and withheld RMSE, and the run's CPU and
# wall time (/usr/bin/time; on a loaded machine quote the CPU: the selection runs its fold fits on
# both threads, so an idle 2-core machine's wall time is about CPU / 2). With GRID=1 the same grid
# is also fitted by hand, candidate by candidate (the best withheld RMSE of the grid, for the
# target "within 1.1× of the best of the grid"; minutes).
#
# Usage: bench/auto_select.sh [build dir] [seed] [extra `piezoid fit` flags…]
#   e.g. bench/auto_select.sh build 37
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
SEED=${2:-37}
shift $(( $# < 2 ? $# : 2 ))
BIN="$BUILD/client/piezoid"
[ -x "$BIN" ] || { echo "no $BIN: build first (scripts/build.sh)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "no /usr/bin/time (Debian: apt-get install time)" >&2; exit 2; }
OUT=${OUT:-$(mktemp -d)}
mkdir -p "$OUT"
"$BIN" synth-stack --out "$OUT/set" --seed "$SEED" --train-s 40 --fs 200 >/dev/null
echo "== real-like stack, seed $SEED: 40 s training at 200 Hz (nproc $(nproc), load $(cut -d' ' -f1 /proc/loadavg))"
/usr/bin/time -f "time: wall %e s, CPU %U + %S s" "$BIN" fit --records "$OUT/set" --family auto --out "$OUT/auto" \
  --no-figures --quiet "$@" 2>&1 | grep -v "^  initial state, \(validate\|test\)"
if [ "${GRID:-0}" = 1 ]; then
  echo "== the grid by hand (withheld RMSE of every candidate, fitted on the training record)"
  python3 - "$OUT/auto/fit.json" <<'PY' | while read -r fam lev eff st; do
import json, sys
s = json.load(open(sys.argv[1]))["selection"]
for c in s["ranking"]:
    print(c["family"], c["levels"] or 12, ",".join(c["effects"]) or "none", c["initial_state"])
PY
    flags=(--records "$OUT/set" --family "$fam" --pi-operators "$lev" --out "$OUT/grid" --no-figures --quiet)
    [ "$eff" != none ] && flags+=(--effects "$eff")
    [ "$st" != auto ] && flags+=(--initial-state "$st")
    "$BIN" fit "${flags[@]}" "$@" >/dev/null
    python3 - "$OUT/grid/fit.json" "$fam $lev $eff $st" <<'PY'
import json, math, sys
r = json.load(open(sys.argv[1]))["records"]
sse = sum(x["rmse"] ** 2 * x["samples"] for x in r if x["role"] != "train")
n = sum(x["samples"] for x in r if x["role"] != "train")
print(f"  {sys.argv[2]}: withheld RMSE {math.sqrt(sse / n):.4g}")
PY
  done
fi
echo "report: $OUT/auto/report.md"
