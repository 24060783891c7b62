#!/usr/bin/env bash
# deploy/systemd without a running systemd (PID 1 here is not systemd):
#  1. `systemd-analyze verify` accepts both units (no warning at all), with ExecStart pointed at
#     this build's programs (verify checks that they exist), and `systemd-analyze security
#     --offline=yes` rates their hardening at most 2.0 ("OK"); skipped when systemd-analyze is
#     missing;
#  2. the command lines the units would run work: Environment= defaults, then the EnvironmentFile
#     (the shipped master.env / worker.env with loopback ports for the test), ${VAR} as one word and
#     $VAR split on spaces as systemd does, STATE_DIRECTORY as StateDirectory= sets it; the master
#     and a worker so started run a synthetic job to its end, and SIGTERM (KillSignal) stops both
#     with status 0 well within TimeoutStopSec.
#   tests/deploy/systemd_test.sh <build dir>
set -uo pipefail
source "$(dirname "$0")/lib.sh"
with_deadline 120 "$@"
need_build "${1:-}"
UNITS=$SRC/deploy/systemd
TMP=$(mktemp -d "${TMPDIR:-/tmp}/pz-systemd.XXXXXX")
PIDS=()
cleanup() {
  local rc=$? pid
  for pid in "${PIDS[@]}"; do stop_pid "$pid" 5; done
  if ((rc != 0 && rc != 77)); then show_logs "$TMP"/*.log; fi
  rm -rf "$TMP"
  exit $rc
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# ---------------------------------------------------------------- 1. systemd-analyze
local_units() {  # the units with this build's programs
  mkdir -p "$TMP/units"
  sed -e "s#/usr/local/bin/piezoid-master#$MASTER#" -e "s#/usr/local/bin/piezoid-worker#$WORKER#" \
    "$UNITS/piezoid-master.service" >"$TMP/units/piezoid-master.service"
  sed -e "s#/usr/local/bin/piezoid-worker#$WORKER#" "$UNITS/piezoid-worker@.service" >"$TMP/units/piezoid-worker@.service"
  cp "$TMP/units/piezoid-worker@.service" "$TMP/units/piezoid-worker@0.service"
}
local_units
if command -v systemd-analyze >/dev/null; then
  for u in piezoid-master.service piezoid-worker@0.service; do
    systemd-analyze verify "$TMP/units/$u" >"$TMP/verify.out" 2>&1
    rc=$?
    if ((rc != 0)) || [[ -s $TMP/verify.out ]]; then cat "$TMP/verify.out"; fail "systemd-analyze verify $u"; fi
    score=$(systemd-analyze security --offline=yes --no-pager "$TMP/units/$u" 2>&1 |
      sed -n 's/.*Overall exposure level for .*: \([0-9.]*\) .*/\1/p')
    [[ -n $score ]] || fail "systemd-analyze security gave no score for $u"
    awk -v s="$score" 'BEGIN { exit !(s <= 2.0) }' || fail "$u: exposure $score > 2.0"
    say "$u: systemd-analyze verify clean, security exposure $score"
  done
else
  say "systemd-analyze is not installed: unit verification skipped (apt-get install systemd)"
fi

# ---------------------------------------------------------------- 2. the command lines
# exec_argv UNIT ENVFILE... : prints ExecStart's argv (one per line) as systemd would build it.
exec_argv() {
  local unit=$1 line val w
  shift
  local -A env=([STATE_DIRECTORY]="$TMP/state")
  while IFS= read -r line; do
    [[ $line =~ ^Environment=([A-Za-z_][A-Za-z0-9_]*)=(.*)$ ]] && env[${BASH_REMATCH[1]}]=${BASH_REMATCH[2]}
  done <"$unit"
  for f in "$@"; do
    while IFS= read -r line; do
      [[ $line =~ ^[[:space:]]*# || ! $line =~ ^([A-Za-z_][A-Za-z0-9_]*)=(.*)$ ]] && continue
      env[${BASH_REMATCH[1]}]=${BASH_REMATCH[2]}
    done <"$f"
  done
  line=$(sed -n 's/^ExecStart=//p' "$unit")
  for w in $line; do
    if [[ $w =~ ^\$\{([A-Za-z_][A-Za-z0-9_]*)\}$ ]]; then
      printf '%s\n' "${env[${BASH_REMATCH[1]}]-}"
    elif [[ $w =~ ^\$([A-Za-z_][A-Za-z0-9_]*)$ ]]; then
      for val in ${env[${BASH_REMATCH[1]}]-}; do printf '%s\n' "$val"; done
    else
      printf '%s\n' "$w"
    fi
  done
}
# The shipped env files, with loopback endpoints on ports the system picks (tcp://127.0.0.1:*: never a
# guessed number, other tests run in parallel), published by the master's --endpoints-file; the
# worker's env file is written from it once the master has bound them.
sed -e "s#^PIEZOID_WORKERS=.*#PIEZOID_WORKERS=tcp://127.0.0.1:*#" -e "s#^PIEZOID_CLIENTS=.*#PIEZOID_CLIENTS=tcp://127.0.0.1:*#" \
  -e "s#^\#*PIEZOID_MASTER_ARGS=.*#PIEZOID_MASTER_ARGS=--endpoints-file $TMP/endpoints#" \
  "$UNITS/master.env" >"$TMP/master.env"
grep -q "^PIEZOID_MASTER_ARGS=--endpoints-file" "$TMP/master.env" || fail "master.env has no PIEZOID_MASTER_ARGS line to set"
mapfile -t M < <(exec_argv "$TMP/units/piezoid-master.service" "$TMP/master.env")
say "master: ${M[*]}"
[[ ${M[0]} == "$MASTER" ]] || fail "ExecStart does not start the master"
mkdir -p "$TMP/state"
"${M[@]}" >"$TMP/master.log" 2>&1 &
MPID=$!
PIDS+=("$MPID")
wait_for 20 "the master publishes its endpoints" test -s "$TMP/endpoints" || fail "the master did not start"
WEP=$(sed -n 1p "$TMP/endpoints") CEP=$(sed -n 2p "$TMP/endpoints")
[[ $WEP == tcp://127.0.0.1:[0-9]* && $CEP == tcp://127.0.0.1:[0-9]* ]] || fail "endpoints file: '$WEP' '$CEP'"
sed -e "s#^PIEZOID_MASTER_WORKERS=.*#PIEZOID_MASTER_WORKERS=$WEP#" "$UNITS/worker.env" >"$TMP/worker.env"
printf 'PIEZOID_WORKER_ARGS=--threads 2 --heartbeat-ms 500\n' >"$TMP/worker-0.env"  # worker-%i.env
mapfile -t W < <(exec_argv "$TMP/units/piezoid-worker@0.service" "$TMP/worker.env" "$TMP/worker-0.env")
say "worker: ${W[*]}"
[[ ${W[0]} == "$WORKER" ]] || fail "ExecStart does not start the worker"
"${W[@]}" >"$TMP/worker.log" 2>&1 &
WPID=$!
PIDS+=("$WPID")
synthetic_spec "systemd unit test" 5 32 0 20 10 >"$TMP/job.json"
ID=$("$CLIENT" submit "$TMP/job.json" --master "$CEP") || fail "submit"
timeout 60 "$CLIENT" watch "$ID" --master "$CEP" >"$TMP/watch.log" 2>&1 || fail "job $ID did not succeed"
say "$(tail -n 2 "$TMP/watch.log" | head -n 1)"
[[ -s $TMP/state/jobs/$ID/checkpoint.pb ]] || fail "no checkpoint in STATE_DIRECTORY"
for p in "$WPID:worker:30" "$MPID:master:60"; do
  IFS=: read -r pid what limit <<<"$p"
  t=$SECONDS
  kill -TERM "$pid"
  wait_for "$limit" "the $what stops on SIGTERM" bash -c "! kill -0 $pid" || fail "the $what ignores SIGTERM"
  wait "$pid"
  rc=$?
  ((rc == 0)) || fail "the $what exited with status $rc on SIGTERM (Restart=on-failure would restart it)"
  say "the $what stopped on SIGTERM with status 0 in $((SECONDS - t)) s (TimeoutStopSec=$limit)"
done
PIDS=()
say "systemd_test: passed"
