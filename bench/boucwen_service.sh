#!/usr/bin/env bash
# The same PSO identification of the Bouc–Wen benchmark (`piezoid boucwen`) locally on 2 threads and
# with every evaluation on the service: a local master and 2 workers of 1 thread each
# (deploy/local/piezoid-local.sh, free ports, a temporary state dir), `piezoid boucwen --master`.
# Prints evaluations, wall time and evaluations/s of both, the size of the session's spec as the
# master stores it, and checks that both report.json files are identical but for the timings.
# Usage: bench/boucwen_service.sh [build dir] [piezoid boucwen flags, replacing the default
#   --algorithm pso --repetitions 1 --train-periods 2 --population 40 --iterations 100 --stall 0]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
shift || true
FLAGS=(--algorithm pso --repetitions 1 --train-periods 2 --population 40 --iterations 100 --stall 0)
[ $# -eq 0 ] || FLAGS=("$@")
BIN="$BUILD/client/piezoid"
for b in "$BIN" "$BUILD/master/piezoid-master" "$BUILD/worker/piezoid-worker"; do
  [ -x "$b" ] || { echo "no $b: build first (scripts/build.sh)" >&2; exit 2; }
done
OUT=$(mktemp -d)
STATE="$OUT/state"
stop() { deploy/local/piezoid-local.sh stop --state-dir "$STATE" >/dev/null 2>&1 || true; rm -rf "$OUT"; }
trap stop EXIT
deploy/local/piezoid-local.sh start --build "$BUILD" --workers 2 --threads 1 --any-port --state-dir "$STATE" \
  --log-level warn >/dev/null
EP=$(deploy/local/piezoid-local.sh endpoint --state-dir "$STATE")
echo "flags: ${FLAGS[*]}"
field() { grep -E "\"$2\": " "$1" | head -1 | sed -E 's/.*: ([^,]*),?$/\1/'; }
run() {  # name, extra flags…
  local name=$1; shift
  local load start end
  load=$(cut -d' ' -f1 /proc/loadavg)
  start=$(date +%s.%N)
  "$BIN" boucwen "${FLAGS[@]}" --no-plots --progress 0 --out "$OUT/$name" "$@" >"$OUT/$name.txt" 2>&1 ||
    { cat "$OUT/$name.txt" >&2; exit 1; }
  end=$(date +%s.%N)
  echo "== $name: $(field "$OUT/$name/report.json" evaluations) evaluations, search $(field "$OUT/$name/report.json" wall_time_s) s" \
       "($(field "$OUT/$name/report.json" evaluations_per_s) evaluations/s), command $(echo "$end - $start" | bc) s," \
       "training RMS $(field "$OUT/$name/report.json" training_rms_m) m (load before $load)"
}
run local --threads 2
run service --master "$EP"
"$BIN" list --master "$EP" | tail -n 2 | sed 's/^/   /'
echo "   stored spec: $(find "$STATE" -name 'spec.pb' -type f -printf '%s bytes\n' | head -1)"
# The reports' keys are in no fixed order: compare them as JSON, without the timings.
python3 - "$OUT/service/report.json" "$OUT/local/report.json" <<'PY'
import json, sys
drop = {"wall_time_s", "evaluations_per_s", "seconds_to_final", "threads", "evaluated_on"}
a, b = ({k: v for k, v in json.load(open(f)).items() if k not in drop} for f in sys.argv[1:])
if a != b:
    sys.exit("report.json: DIFFERENT on the service and locally: " +
             ", ".join(k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)))
print("report.json: identical on the service and locally (but for timings, threads and where)")
PY
