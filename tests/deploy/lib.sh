# Helpers of the deployment tests (sourced). Every wait is bounded; cleanup runs from an EXIT trap.
# Exit code 77 = skipped (SKIP_RETURN_CODE in tests/CMakeLists.txt).
# shellcheck shell=bash

SRC=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
T0=$SECONDS

# with_deadline SECONDS ARGS...: re-runs this script under `timeout`, so that past SECONDS it gets a
# SIGTERM and its EXIT trap still cleans up (ctest's own TIMEOUT, set above this, would kill it
# outright). Call it first thing, with the script's arguments.
with_deadline() {
  local limit=$1
  shift
  [[ -n ${PZ_DEADLINE:-} ]] && return 0
  PZ_DEADLINE=$limit exec timeout -k 30 "$limit" bash "$0" "$@"
}

say() { printf '[%4ds] %s\n' "$((SECONDS - T0))" "$*"; }
skip() { echo "SKIPPED: $*"; exit 77; }
fail() { echo "FAIL: $*"; exit 1; }

# need_build DIR: the programs of a build folder, as MASTER, WORKER, CLIENT.
need_build() {
  BUILD=$(cd "${1:-$SRC/build}" 2>/dev/null && pwd) || fail "build folder ${1:-} not found"
  MASTER=$BUILD/master/piezoid-master
  WORKER=$BUILD/worker/piezoid-worker
  CLIENT=$BUILD/client/piezoid
  local x
  for x in "$MASTER" "$WORKER" "$CLIENT"; do [[ -x $x ]] || fail "$x not built"; done
}

# need_root WHY: skip unless root.
need_root() { [[ $(id -u) -eq 0 ]] || skip "needs root ($*)"; }

# need_commands "cmd:package ..." : installs the Debian packages of the missing commands
# (idempotent; apt-get update only when something is missing and the first try fails); skips
# the test when that is impossible.
need_commands() {
  local pair missing=()
  for pair in "$@"; do command -v "${pair%%:*}" >/dev/null || missing+=("${pair#*:}"); done
  ((${#missing[@]})) || return 0
  command -v apt-get >/dev/null || skip "missing ${missing[*]} and no apt-get"
  say "installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null 2>&1 ||
    { apt-get update -qq >/dev/null 2>&1 &&
      apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null 2>&1; } ||
    skip "cannot install ${missing[*]} with apt-get"
  for pair in "$@"; do command -v "${pair%%:*}" >/dev/null || skip "${pair%%:*} still missing after installing ${pair#*:}"; done
}

# wait_for SECONDS WHAT COMMAND...: polls COMMAND every 0.1 s until it succeeds; fails after SECONDS.
wait_for() {
  local limit=$1 what=$2 end
  shift 2
  end=$(($(date +%s%N) + limit * 1000000000))
  until "$@" >/dev/null 2>&1; do
    (($(date +%s%N) < end)) || { say "timeout after ${limit} s: $what"; return 1; }
    sleep 0.1
  done
}

# stop_pid PID [SECONDS]: SIGTERM, bounded wait, then SIGKILL. Only for processes the test started.
stop_pid() {
  local pid=$1 limit=${2:-10} i
  [[ -n $pid ]] && kill -0 "$pid" 2>/dev/null || return 0
  kill -TERM "$pid" 2>/dev/null
  for ((i = 0; i < limit * 10; i++)); do kill -0 "$pid" 2>/dev/null || return 0; sleep 0.1; done
  kill -KILL "$pid" 2>/dev/null
  return 0
}

# show_logs FILE...: the end of each log (after a failure or timeout).
show_logs() {
  local f
  for f in "$@"; do
    [[ -f $f ]] || continue
    echo "----- $f (last 40 lines)"
    tail -n 40 "$f"
  done
}

# comparable DIR: what must be bit-identical between two runs of one spec in a fetched result:
# best.csv (synthetic jobs) or the best networks (hgann: networks/*.json, validation.csv) without
# their provenance (job id, time of writing), and progress.csv without its wall-clock column (12).
comparable() {
  local d=$1 f
  for f in "$d"/best.csv "$d"/networks/*.json "$d"/network.json "$d"/validation.csv; do
    [[ -f $f ]] && { echo "== ${f#"$d"/}"; grep -Ev '^ *"(job_id|created)":' "$f"; }
  done
  echo "== progress.csv without wall_time_s"
  sed -E 's/^(([^,]*,){11})[^,]*,/\1/' "$d/progress.csv"
}

# same_result A B: A and B (fetch folders) hold the same individuals and generation log.
same_result() {
  [[ -s $1/progress.csv && -s $2/progress.csv ]] || fail "no progress.csv in $1 or $2"
  if ! diff <(comparable "$1") <(comparable "$2") >"$1.diff"; then
    head -n 40 "$1.diff"
    fail "the results in $1 and $2 differ"
  fi
  say "bit-identical to the reference: $(($(wc -l <"$1/progress.csv") - 1)) generations, best cost $(tail -n 1 "$1/progress.csv" | cut -d, -f2)"
}

# hosts_up PREFIX "IP ..." : "hosts" on one machine: a network namespace PREFIX-br holding a
# bridge br0, and one namespace per address (PREFIX-h1, PREFIX-h2, ...) joined to it by a veth pair
# (eth0 inside, port<i> on the bridge) with that address /24. Sets NS_BR and NS (the hosts'
# namespaces, in order); hosts_down deletes them all (for the EXIT trap). Skips the test where
# network namespaces cannot be made.
NS_BR="" NS=()
hosts_up() {
  local i ips
  read -r -a ips <<<"$2"
  NS_BR=$1-br
  ip netns add "$NS_BR" 2>/dev/null || { NS_BR=""; skip "cannot create network namespaces here"; }
  ip -n "$NS_BR" link add br0 type bridge && ip -n "$NS_BR" link set br0 up || fail "bridge"
  for i in "${!ips[@]}"; do
    NS+=("$1-h$((i + 1))")
    ip netns add "${NS[i]}" || fail "netns ${NS[i]}"
    ip -n "$NS_BR" link add "port$i" type veth peer name eth0 netns "${NS[i]}" || fail "veth $i"
    ip -n "$NS_BR" link set "port$i" master br0 up
    ip -n "${NS[i]}" link set lo up
    ip -n "${NS[i]}" addr add "${ips[i]}/24" dev eth0
    ip -n "${NS[i]}" link set eth0 up
  done
}
hosts_down() {
  local n
  for n in "${NS[@]}" ${NS_BR:+"$NS_BR"}; do ip netns del "$n" 2>/dev/null; done
  NS=() NS_BR=""
}

# synthetic_spec NAME SEED BITS SLEEP_MS POPULATION GENERATIONS: a synthetic job spec (JSON) on
# stdout. With SLEEP_MS > 0 a run is paced by time rather than by the (shared) cores.
synthetic_spec() {
  cat <<EOF
{
  "version": 1,
  "name": "$1",
  "seed": "$2",
  "synthetic": { "cost": "COST_FUNCTION", "genome_bits": $3, "sleep_ms": $4 },
  "ga": { "population": $5, "elite_fraction": 0.5, "tournament": 2, "crossover_probability": 1.0,
          "mutation_probability": 0.02, "generations": $6, "stall_generations": 0 },
  "limits": { "task_timeout_s": 20, "quarantine_after": 3, "penalty_cost": 1e9 }
}
EOF
}

# reference_run SPEC OUT THREADS: the same spec on a master + one worker on loopback (free ports),
# fetched into OUT (logs in OUT.log); non-zero on failure. May run in the background: SIGTERM
# stops it and its processes.
reference_run() {
  local spec=$1 out=$2 threads=$3 dir="$2.run" mpid="" wpid="" cpid="" id cep rc=0
  trap 'stop_pid "$cpid" 2; stop_pid "$wpid" 2; stop_pid "$mpid" 2; exit 143' TERM
  mkdir -p "$dir"
  "$MASTER" --workers 'tcp://127.0.0.1:*' --clients 'tcp://127.0.0.1:*' --state-dir "$dir/state" \
    --endpoints-file "$dir/endpoints" --log-level warn >>"$out.log" 2>&1 &
  mpid=$!
  if wait_for 20 "reference master" test -s "$dir/endpoints"; then
    "$WORKER" --master "$(sed -n 1p "$dir/endpoints")" --threads "$threads" --log-level warn >>"$out.log" 2>&1 &
    wpid=$!
    cep=$(sed -n 2p "$dir/endpoints")
    # The client in the background and `wait`: a SIGTERM is handled at once.
    run() { timeout 300 "$@" --master "$cep" >>"$out.log" 2>&1 & cpid=$!; wait "$cpid"; }
    id=$("$CLIENT" submit "$spec" --master "$cep" 2>>"$out.log") && run "$CLIENT" watch "$id" &&
      run "$CLIENT" fetch "$id" --out "$out" --no-plots || rc=1
  else
    rc=1
  fi
  stop_pid "$wpid"
  stop_pid "$mpid"
  ((rc == 0)) || show_logs "$out.log"
  return $rc
}
