#!/usr/bin/env bash
# Several hosts on one machine: three network namespaces h1, h2, h3 on a bridge (the bridge in a
# fourth namespace; the addresses 198.18.0.1-3, a benchmarking range, exist only inside them). The
# master runs on h1, one worker on h2 and one on h3. Once the job is under way, h3's link is cut
# (its bridge port set down: a pulled cable, the worker's TCP connection just goes silent) for
# 30 s: the master must declare h3's worker dead, re-queue its lease and go on with h2 alone; then
# the link comes back, h3's worker must rejoin, and the job must complete with a result
# bit-identical to the same spec run on loopback (best individuals, generation log).
# Needs root, ip (iproute2) and network namespaces; else exit 77 = skipped.
#   tests/deploy/netns_test.sh <build dir>
set -uo pipefail
source "$(dirname "$0")/lib.sh"
with_deadline 240 "$@"
need_build "${1:-}"
need_root "network namespaces"
need_commands ip:iproute2
CUT_S=${PZ_NETNS_CUT_S:-30}

TMP=$(mktemp -d "${TMPDIR:-/tmp}/pz-netns.XXXXXX")
IP=(198.18.0.1 198.18.0.2 198.18.0.3)
PIDS=()
cleanup() {
  local rc=$? pid
  for pid in "${PIDS[@]}"; do stop_pid "$pid" 5; done
  hosts_down
  if ((rc != 0 && rc != 77)); then show_logs "$TMP"/*.log; fi
  rm -rf "$TMP"
  exit $rc
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# ---------------------------------------------------------------- the hosts
hosts_up "pz$$" "${IP[*]}"
# `ip netns exec` execs the program: in the background, $! is the program's pid.
on() { ip netns exec "$@"; }
say "hosts: ${NS[*]} on bridge br0 in $NS_BR: ${IP[*]}"

# ---------------------------------------------------------------- the job
# Evaluations sleep 25 ms each: the run is paced by time, not by the two shared cores. One thread
# per worker: >= 0.6 s a generation for h2 alone, so the job outlasts the 30 s cut.
synthetic_spec "netns partition test" 20240613 96 25 48 70 >"$TMP/job.json"
# The reference: the same spec on loopback, concurrently (it sleeps most of the time).
reference_run "$TMP/job.json" "$TMP/reference" 8 &
REF_PID=$!
PIDS+=("$REF_PID")

FAST=(--heartbeat-ms 200 --liveness 5)
ip netns exec "${NS[0]}" "$MASTER" --workers "tcp://${IP[0]}:*" --clients "tcp://${IP[0]}:*" \
  --state-dir "$TMP/state" --endpoints-file "$TMP/endpoints" "${FAST[@]}" --log-level info >"$TMP/master.log" 2>&1 &
PIDS+=($!)
wait_for 20 "the master binds on h1" test -s "$TMP/endpoints" || fail "no master"
WEP=$(sed -n 1p "$TMP/endpoints") CEP=$(sed -n 2p "$TMP/endpoints")  # ports the system picked
for i in 1 2; do
  ip netns exec "${NS[i]}" "$WORKER" --master "$WEP" --threads 1 "${FAST[@]}" --backoff-max-ms 1000 \
    --log-level info >"$TMP/worker-h$((i + 1)).log" 2>&1 &
  PIDS+=($!)
done
cli() { on "${NS[0]}" "$CLIENT" "$@" --master "$CEP"; }
workers() { cli list 2>/dev/null | sed -n '1s/^\([0-9]*\) worker.*/\1/p'; }
has_workers() { [[ $(workers) == "$1" ]]; }
wait_for 20 "both workers (h2, h3) registered" has_workers 2 || fail "workers did not connect across the bridge"
say "master on h1, workers on h2 and h3 connected over the bridge"

ID=$(cli submit "$TMP/job.json") || fail "submit"
say "job $ID submitted"
generation() { cli status "$ID" 2>/dev/null | sed -n 's/.* gen *\([0-9]*\)\/.*/\1/p'; }
at_least() { local g; g=$(generation); [[ -n $g ]] && ((g >= $1)); }
wait_for 60 "generation 5" at_least 5 || fail "the job does not progress"

# ---------------------------------------------------------------- cut h3 off
g0=$(generation)
ip -n "$NS_BR" link set port2 down
t_cut=$SECONDS
say "h3 cut off (bridge port down) at generation $g0, for $CUT_S s"
wait_for 10 "the master drops h3's worker" has_workers 1 || fail "the master still counts 2 workers"
say "the master counts 1 worker after $((SECONDS - t_cut)) s"
sleep $((CUT_S - (SECONDS - t_cut) > 0 ? CUT_S - (SECONDS - t_cut) : 0))
g1=$(generation)
((g1 > g0)) || fail "no progress while h3 was cut off (generation $g0 -> $g1)"
say "generation $g0 -> $g1 during the cut (h2 alone)"
cli status "$ID" | grep -q running || fail "the job ended during the cut: make it longer"
ip -n "$NS_BR" link set port2 up
t_up=$SECONDS
say "h3 reconnected (bridge port up)"
wait_for 30 "h3's worker rejoins" has_workers 2 || fail "h3's worker did not rejoin"
say "h3's worker rejoined after $((SECONDS - t_up)) s"

# ---------------------------------------------------------------- to the end, then compare
ip netns exec "${NS[0]}" "$CLIENT" watch "$ID" --master "$CEP" --timeout-ms 10000 >"$TMP/watch.log" 2>&1 &
WATCH=$!
PIDS+=("$WATCH")
end=$((SECONDS + 120))
while kill -0 "$WATCH" 2>/dev/null && ((SECONDS < end)); do sleep 0.2; done
kill -0 "$WATCH" 2>/dev/null && fail "the job did not end within 120 s of the reconnection"
wait "$WATCH" || { cat "$TMP/watch.log"; fail "the job did not succeed"; }
tail -n 2 "$TMP/watch.log"
cli fetch "$ID" --out "$TMP/result" --no-plots >/dev/null || fail "fetch"
wait "$REF_PID" || fail "the reference run failed"
same_result "$TMP/result" "$TMP/reference"
for pid in "${PIDS[@]}"; do stop_pid "$pid" 5; done
PIDS=()
say "what the master saw of the workers:"
grep -E "worker [0-9a-f]+ (ready|removed|missed)" "$TMP/master.log" | cut -c12-150 | sed 's/^/    /'
say "what h3's worker saw:"
grep -E "reconnecting|stopped:" "$TMP/worker-h3.log" | sort -u -k4 | cut -c12-150 | sed 's/^/    /'
grep -q "stopped: .*[1-9][0-9]* reconnects" "$TMP/worker-h3.log" || fail "h3's worker did not reconnect"
say "netns_test: passed"
