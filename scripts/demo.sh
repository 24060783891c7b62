#!/usr/bin/env bash
# The main job: installs what is missing, builds, then runs the bundled HGANN identification
# (examples/hgann_job.json: the nine bench cases of data/bimorph-fin/nominal with the robust
# settings, 4 islands of 400 and trend seeds; well under a minute on 2 cores) as a real
# service session on this machine: a piezoid-master and 2 piezoid-workers
# (deploy/local/piezoid-local.sh), `piezoid submit`, `piezoid watch` (progress bar), `piezoid fetch`
# into out/demo/result (networks and the validation report), `piezoid export` (C header); the
# processes are stopped again at the end, on Ctrl-C or on an error.
#   scripts/demo.sh [job.json]    (default examples/hgann_job.json; examples/hgann_quick.json: seconds)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
scripts/build.sh
BUILD="${PIEZOID_BUILD_DIR:-build}"
BIN="$BUILD/client/piezoid"
JOB="${1:-examples/hgann_job.json}"
OUT=out/demo
STATE="$OUT/state"
RESULT="$OUT/result"
LAUNCH=(deploy/local/piezoid-local.sh)

stop() { "${LAUNCH[@]}" stop --state-dir "$STATE" --build "$BUILD" || true; }
trap stop EXIT
trap 'echo; echo "demo: interrupted"; exit 130' INT TERM

rm -rf "$STATE" "$RESULT"
mkdir -p "$OUT"
echo
echo "== a piezoid-master and 2 piezoid-workers on this machine (deploy/local/piezoid-local.sh)"
"${LAUNCH[@]}" start --workers 2 --threads 1 --any-port --state-dir "$STATE" --build "$BUILD" --log-level warn
MASTER=$("${LAUNCH[@]}" endpoint --state-dir "$STATE" --build "$BUILD")

echo
echo "== piezoid submit $JOB"
ID=$("$BIN" submit "$JOB" --master "$MASTER")
echo "job $ID"

echo
echo "== piezoid watch $ID"
"$BIN" watch "$ID" --master "$MASTER"

echo
echo "== piezoid fetch $ID --out $RESULT"
"$BIN" fetch "$ID" --best 5 --out "$RESULT" --master "$MASTER"

echo
echo "== piezoid export $RESULT/network.pb (the best network as a C header for a controller)"
"$BIN" export "$RESULT/network.pb" --out "$RESULT/hgann_network.h" --name hgann_predict

echo
echo "demo: the report is $RESULT/report.md (networks in $RESULT/networks, C header $RESULT/hgann_network.h);"
echo "      logs of the master and workers in $STATE/run"
