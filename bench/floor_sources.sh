#!/usr/bin/env bash
# The noise floor of issue 45, each source (repeats, the settled rest, periods) and the one used, on
# the two real-like generators' sets (synth/reallike.h; synth/reallike_ring.h: a 10 kHz stage
# whose rests ring and settle, chatter drives recorded three times), the bundled P-885.91 stack and
# any other record set given (a local real recording). `piezoid records` prints them.
#
# Usage: bench/floor_sources.sh [build dir] [record set…]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
shift $(( $# < 1 ? $# : 1 ))
BIN="$BUILD/client/piezoid"
[ -x "$BIN" ] || { echo "no $BIN: build first (scripts/build.sh)" >&2; exit 2; }
OUT=${OUT:-$(mktemp -d)}
for seed in 1 2; do
  "$BIN" synth-stack --ringing --out "$OUT/ringing-$seed" --seed "$seed" | sed "s/^/ringing $seed: /"
done
"$BIN" synth-stack --out "$OUT/reallike-37" --seed 37 | sed "s/^/reallike 37: /"
for s in "$OUT/ringing-1" "$OUT/ringing-2" "$OUT/reallike-37" data/yan9a-p885-stack "$@"; do
  echo "== $s"
  "$BIN" records "$s" | sed -n '/^noise floor/,$p'
done
