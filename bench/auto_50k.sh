#!/usr/bin/env bash
# The budget of `piezoid fit --family auto` (issue 45: within 2 minutes on 2 cores for 50 k training
# samples): a real-like stack (synth/reallike.h) recorded at 10 kHz, 5 s of training sine after a
# rest at the bottom of the range (50 001 samples), 2 s withheld records; the selection's wall and
# CPU time (/usr/bin/time). On a loaded machine quote the CPU: the folds run on both threads, so an
# idle 2-core machine's wall time is about CPU / 2.
#
# Usage: bench/auto_50k.sh [build dir] [seed] [extra `piezoid fit` flags…]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
SEED=${2:-45}
shift $(( $# < 2 ? $# : 2 ))
BIN="$BUILD/client/piezoid"
[ -x "$BIN" ] || { echo "no $BIN: build first (scripts/build.sh)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "no /usr/bin/time (Debian: apt-get install time)" >&2; exit 2; }
OUT=${OUT:-$(mktemp -d)}
"$BIN" synth-stack --out "$OUT/set" --seed "$SEED" --fs 10000 --train-s 5 --withheld-s 2 >/dev/null
"$BIN" records "$OUT/set" | head -3
echo "== fit --family auto (nproc $(nproc), load $(cut -d' ' -f1 /proc/loadavg))"
/usr/bin/time -f "time: wall %e s, CPU %U + %S s" "$BIN" fit --records "$OUT/set" --family auto \
  --out "$OUT/auto" --no-figures --quiet "$@" 2>&1 | grep -E "model selection|chosen \(|^  (train|validate|test)|^time"
