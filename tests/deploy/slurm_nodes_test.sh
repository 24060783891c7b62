#!/usr/bin/env bash
# deploy/slurm/piezoid.sbatch on a two-node Slurm: the nodes n1 and n2 are network namespaces on a
# bridge (addresses 198.18.1.1-2 only inside them), each with its own host name (UTS namespace) and
# /etc/hosts (mount namespace); slurmctld and one slurmd run on n1, a slurmd on n2. A two-node
# allocation must start the master on n1, publish n1's NodeAddr, and run a worker on each node
# that reaches the master across the bridge; the job (examples/hgann_quick.json) must complete
# with the result of a loopback run.
# Needs root, iproute2, util-linux (unshare, nsenter) and Debian's Slurm packages; else exit 77.
#   tests/deploy/slurm_nodes_test.sh <build dir>
set -uo pipefail
source "$(dirname "$0")/lib.sh"
with_deadline 180 "$@"
need_build "${1:-}"
need_root "network namespaces, munged, slurmctld and slurmd"
need_commands slurmctld:slurmctld slurmd:slurmd sbatch:slurm-client munged:munge ss:iproute2 ip:iproute2 \
  unshare:util-linux nsenter:util-linux
source "$(dirname "$0")/slurm_lib.sh"

TMP=$(mktemp -d "${TMPDIR:-/tmp}/pz-slurm-nodes.XXXXXX")
NODES=(n1 n2) IP=(198.18.1.1 198.18.1.2)
REF_PID="" SL="" MU="" SH=""
cleanup() {
  local rc=$?
  stop_pid "$REF_PID" 5
  if ((rc != 0 && rc != 77)); then show_logs "$SL"/*.log "$SH"/*.out "$TMP"/*.log; fi
  slurm_stop
  hosts_down
  rm -rf "$TMP"
  exit $rc
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# ---------------------------------------------------------------- the two hosts
hosts_up "pz$$" "${IP[*]}"
printf '127.0.0.1 localhost\n%s n1\n%s n2\n' "${IP[0]}" "${IP[1]}" >"$TMP/hosts"
# on_node I COMMAND...: COMMAND on node I: its network, its host name, its /etc/hosts. Only the
# network namespace is entered (`ip netns exec` would remount /sys, which slurmd needs).
on_node() {
  local i=$1
  shift
  nsenter --net="/run/netns/${NS[i]}" unshare --uts --mount \
    bash -c 'mount --bind "$0" /etc/hosts && hostname "$1" && shift && exec "$@"' \
    "$TMP/hosts" "${NODES[i]}" "$@"
}
[[ $(on_node 1 hostname 2>/dev/null) == n2 ]] || skip "cannot enter a network namespace with its own host name here"
SL_PREFIX=(ip netns exec "${NS[0]}")
say "nodes n1 (${IP[0]}) and n2 (${IP[1]}) on a bridge"

# ---------------------------------------------------------------- munge + Slurm on the two nodes
slurm_init "$TMP"
slurm_conf "n1(${IP[0]})" "NodeName=n1 NodeAddr=${IP[0]} CPUs=4 State=UNKNOWN
NodeName=n2 NodeAddr=${IP[1]} CPUs=4 State=UNKNOWN
PartitionName=test Nodes=n1,n2 Default=YES MaxTime=INFINITE State=UP"
on_node 0 slurmctld -c || fail "slurmctld"
on_node 0 slurmd -N n1 || fail "slurmd n1"
on_node 1 slurmd -N n2 || fail "slurmd n2"
wait_for 30 "both nodes idle" nodes_idle 2 || { sl sinfo -N; fail "Slurm did not come up"; }
say "$(sinfo --version): $(sl sinfo -h -o '%D nodes %T: %N')"

reference_run "$SRC/examples/hgann_quick.json" "$TMP/reference" 2 &
REF_PID=$!

# ---------------------------------------------------------------- one allocation over both nodes
export PIEZOID_BIN=$BUILD PIEZOID_THREADS=1 PIEZOID_STATE=$SH/state
J=$(sl sbatch --parsable --chdir="$SH" --nodes=2 --time=5 "$SRC/deploy/slurm/piezoid.sbatch" \
  "$SRC/examples/hgann_quick.json") || fail "sbatch"
say "job $J: sbatch --nodes=2 piezoid.sbatch examples/hgann_quick.json"
wait_for 120 "job $J ends" is_final "$J" || fail "job $J did not end"
out=$SH/piezoid-$J.out
grep -h "piezoid-slurm" "$out" | sed 's/^/    /'
[[ $(job_state "$J") == COMPLETED ]] || fail "job $J: $(job_state "$J"), exit $(job_field "$J" ExitCode)"
grep -q "piezoid-slurm: job $J: master on n1 (${IP[0]})" "$out" || fail "the master did not run on n1 at ${IP[0]}"
grep -q "workers connect to tcp://${IP[0]}:" "$out" || fail "the workers were not given n1's address"
for n in n1 n2; do
  grep -qE "worker [0-9a-f]+ ready: 1 threads, host $n pid" "$out" || fail "no worker from $n joined the master"
done
say "the master on n1 had a worker from n1 and one from n2:"
grep -E "worker [0-9a-f]+ ready|stopped: [0-9]+ tasks" "$out" | cut -c12-150 | sed 's/^/    /'
[[ $(grep -cE "stopped: [1-9][0-9]* tasks" "$out") -eq 2 ]] || fail "not both workers evaluated individuals"
wait "$REF_PID" || fail "the reference run failed"
REF_PID=""
same_result "$(find "$SH/state/results" -mindepth 1 -maxdepth 1 -type d | head -n 1)" "$TMP/reference"
say "slurm_nodes_test: passed"
