#!/usr/bin/env bash
# bench/retention_memory.sh [N=12]: resident memory of a master holding N ended hgann jobs
# (examples/hgann_quick.json) in memory, after a restart with all of them loaded (--keep-in-memory
# 1000), and after a restart with all of them archived (--keep-in-memory 0). docs/performance.md.
set -euo pipefail
cd "$(dirname "$0")/.."
B=${PIEZOID_BUILD_DIR:-build}; S=$(mktemp -d); N=${1:-12}
start_master() { "$B/master/piezoid-master" --workers 'tcp://127.0.0.1:*' --clients 'tcp://127.0.0.1:*' --state-dir "$S/state" --endpoints-file "$S/ep" --log-level warn "$@" > "$S/m.log" 2>&1 & MP=$!; for i in $(seq 100); do [ -s "$S/ep" ] && break; sleep 0.1; done; WE=$(sed -n 1p "$S/ep"); CE=$(sed -n 2p "$S/ep"); }
rss() { awk '/VmRSS/ {print $2}' /proc/$1/status; }
start_master --keep-in-memory 1000
"$B/worker/piezoid-worker" --master "$WE" --threads 2 --log-level warn > "$S/w.log" 2>&1 & WP=$!
echo "idle master: $(rss $MP) kB"
for k in $(seq $N); do id=$("$B/client/piezoid" submit examples/hgann_quick.json --client-token "t$k" --master "$CE"); "$B/client/piezoid" watch "$id" --master "$CE" > /dev/null; done
echo "master holding $N ended jobs in memory: $(rss $MP) kB"
kill -TERM $MP; wait $MP || true; rm -f "$S/ep"
start_master --keep-in-memory 1000; sleep 1; "$B/client/piezoid" list --master "$CE" > /dev/null
echo "restarted, keep 1000 (all loaded): $(rss $MP) kB"
kill -TERM $MP; wait $MP || true; rm -f "$S/ep"
start_master --keep-in-memory 0; sleep 1; "$B/client/piezoid" list --master "$CE" > /dev/null
echo "restarted, keep 0 (all archived): $(rss $MP) kB"
"$B/client/piezoid" list --master "$CE" | tail -2
kill -TERM $MP $WP; wait || true; rm -rf "$S"
