#!/usr/bin/env bash
# deploy/slurm on a real single-node Slurm (Debian's slurmctld, slurmd, munge), started by this test
# without systemd, with its config, state, munge socket and logs in a temporary folder
# (SLURM_CONF; /etc/slurm and any system munged are left alone):
#  A. `sbatch deploy/slurm/piezoid.sbatch examples/hgann_quick.json` runs the HGANN identification
#     to its end: master in the batch step, workers through srun; the fetched result is
#     bit-identical to the same spec run on loopback.
#  B. the same script with a real time limit (--time=1 --signal=B:TERM@30: Slurm itself sends the
#     SIGTERM) stops mid-job: workers, then master, state left; exit 143. Resubmitted with the same
#     state directory, it resumes the job (not a new one), while deploy/slurm/piezoid-workers.sbatch
#     adds a worker from a second allocation (it finds the master through the state directory and
#     stops by itself when that master's allocation ends); the result is bit-identical to the
#     uninterrupted loopback run.
# Needs root and apt-get (installs slurmctld slurmd slurm-client munge if missing); else exit 77.
#   tests/deploy/slurm_test.sh <build dir>
set -uo pipefail
source "$(dirname "$0")/lib.sh"
with_deadline 240 "$@"
need_build "${1:-}"
need_root "starts munged, slurmctld and slurmd"
need_commands slurmctld:slurmctld slurmd:slurmd sbatch:slurm-client munged:munge ss:iproute2

source "$(dirname "$0")/slurm_lib.sh"

TMP=$(mktemp -d "${TMPDIR:-/tmp}/pz-slurm.XXXXXX")
REF_PIDS=() SL="" MU="" SH=""
cleanup() {
  local rc=$? pid
  for pid in "${REF_PIDS[@]}"; do stop_pid "$pid" 5; done
  if ((rc != 0 && rc != 77)); then show_logs "$SL"/*.log "$SH"/*.out "$TMP"/*.log; fi
  slurm_stop
  rm -rf "$TMP"
  exit $rc
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# ---------------------------------------------------------------- munge + Slurm
slurm_init "$TMP"
slurm_conf localhost "NodeName=localhost CPUs=8 State=UNKNOWN
PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP"
slurmctld -c || fail "slurmctld"
T_CTLD=$(date +%s)
slurmd -N localhost || fail "slurmd"
wait_for 20 "the node is idle" nodes_idle 1 || fail "Slurm did not come up"
say "$(sinfo --version) single node up: $(sinfo -h -o '%P %a %D %T %N')"

# master_cli STATE ARGS...: the client against the master that STATE's master.env names.
master_cli() {
  local env=$1/run/master.env
  shift
  [[ -s $env ]] || return 1
  "$CLIENT" "$@" --master "$(sed -n 's/^PIEZOID_MASTER=//p' "$env")" --timeout-ms 1000 --retries 1
}

export PIEZOID_BIN=$BUILD PIEZOID_THREADS=2 PIEZOID_BIND=127.0.0.1 PIEZOID_STOP_S=20
SBATCH=(sbatch --parsable --chdir="$SH" --exclusive=user --nodes=1)

# ---------------------------------------------------------------- the jobs and their references
# Paced by a 20 ms sleep per evaluation: 90 generations of 20 new individuals (40 at first).
synthetic_spec "slurm time-limit test" 4711 80 20 40 90 >"$TMP/long.json"
QUICK=$SRC/examples/hgann_quick.json
if [[ ! -f $QUICK ]]; then
  say "note: examples/hgann_quick.json is missing: part A runs examples/synthetic_job.json"
  QUICK=$SRC/examples/synthetic_job.json
fi
reference_run "$QUICK" "$TMP/ref-quick" 2 &
REF_PIDS+=($!)
reference_run "$TMP/long.json" "$TMP/ref-long" 8 &
REF_PIDS+=($!)

# ---------------------------------------------------------------- A. hgann_quick to its end
export PIEZOID_STATE=$SH/state-a
A=$("${SBATCH[@]}" --time=10 "$SRC/deploy/slurm/piezoid.sbatch" "$QUICK") || fail "sbatch A"
say "A: job $A: piezoid.sbatch ${QUICK#"$SRC"/}"
wait_for 120 "job $A ends" is_final "$A" || fail "job $A did not end"
[[ $(job_state "$A") == COMPLETED ]] || fail "job $A: $(job_state "$A"), exit $(job_field "$A" ExitCode)"
say "A: COMPLETED (elapsed $(job_field "$A" RunTime))"
grep -h "piezoid-slurm" "$SH/piezoid-$A.out" | sed 's/^/    /'
wait "${REF_PIDS[0]}" || fail "the reference run of hgann_quick failed"
RES_A=$(find "$SH/state-a/results" -mindepth 1 -maxdepth 1 -type d | head -n 1)
[[ -n $RES_A ]] || fail "job $A fetched no result"
same_result "$RES_A" "$TMP/ref-quick"

# ---------------------------------------------------------------- B1. a real time limit mid-job
export PIEZOID_STATE=$SH/state-b
# slurmctld checks time limits every 30 s from its start; with --time=1 and --signal=B:TERM@30 the
# signal comes at the first check after the job starts. Start the job ~12 s before a check.
phase=$((($(date +%s) - T_CTLD) % 30))
((phase <= 17)) && sleep $((17 - phase)) || sleep $((47 - phase))
# One thread: the job needs >= 90 x 20 x 20 ms = 36 s, more than one period, so it is still
# running when the signal comes even if the start misses the aimed-at check.
B1=$(PIEZOID_THREADS=1 "${SBATCH[@]}" --time=1 --signal=B:TERM@30 "$SRC/deploy/slurm/piezoid.sbatch" "$TMP/long.json") ||
  fail "sbatch B1"
say "B1: job $B1: --time=1 --signal=B:TERM@30 piezoid.sbatch long.json (1 worker thread)"
last_gen=0
end=$((SECONDS + 90))
until is_final "$B1"; do
  ((SECONDS < end)) || fail "job $B1 did not end within 90 s"
  g=$(master_cli "$PIEZOID_STATE" list 2>/dev/null | sed -n 's/.* gen *\([0-9]*\)\/.*/\1/p' | head -n 1)
  [[ -n $g ]] && last_gen=$g
  sleep 0.3
done
out=$SH/piezoid-$B1.out
grep -h "piezoid-slurm" "$out" | sed 's/^/    /'
[[ $(job_field "$B1" ExitCode) == 143:0 ]] || fail "job $B1: exit $(job_field "$B1" ExitCode), expected 143:0 (stopped by the signal)"
grep -q "SIGTERM (time limit or scancel): shutting down" "$out" || fail "job $B1 was not stopped by the time-limit signal"
for step in "stopping the workers" "stopping the master" "stopped$"; do
  grep -q "piezoid-slurm: $step" "$out" || fail "job $B1: no '$step' in its output"
done
grep -q "did not stop within" "$out" && fail "job $B1: a process had to be killed"
ckpt=$(find "$PIEZOID_STATE/jobs" -name checkpoint.pb | head -n 1)
[[ -s $ckpt ]] || fail "job $B1 left no checkpoint"
[[ -e $PIEZOID_STATE/run/master.env ]] && fail "job $B1 left master.env behind"
((last_gen >= 1 && last_gen < 90)) || fail "job $B1: stopped at generation $last_gen, not mid-job"
say "B1: stopped by Slurm's time-limit signal after $(job_field "$B1" RunTime) at generation ~$last_gen/90; checkpoint kept"

# ---------------------------------------------------------------- B2. resubmit: resume + more workers
B2=$("${SBATCH[@]}" --time=10 "$SRC/deploy/slurm/piezoid.sbatch" "$TMP/long.json") || fail "sbatch B2"
W=$("${SBATCH[@]}" --time=10 "$SRC/deploy/slurm/piezoid-workers.sbatch") || fail "sbatch workers"
say "B2: job $B2 (same command, same state) and job $W (piezoid-workers.sbatch)"
max_workers=0
end=$((SECONDS + 120))
until is_final "$B2"; do
  ((SECONDS < end)) || fail "job $B2 did not end within 120 s"
  n=$(master_cli "$PIEZOID_STATE" list 2>/dev/null | sed -n '1s/^\([0-9]*\) worker.*/\1/p')
  [[ -n $n ]] && ((n > max_workers)) && max_workers=$n
  sleep 0.3
done
grep -h "piezoid-slurm" "$SH/piezoid-$B2.out" | sed 's/^/    /'
[[ $(job_state "$B2") == COMPLETED ]] || fail "job $B2: $(job_state "$B2"), exit $(job_field "$B2" ExitCode)"
grep -q "submitted before; resuming" "$SH/piezoid-$B2.out" || fail "job $B2 did not resume the job of $B1"
resumed=$(sed -n 's/.*: resuming after generation \([0-9]*\).*/\1/p' "$SH/piezoid-$B2.out" | head -n 1)
[[ -n $resumed ]] && ((resumed >= last_gen && resumed < 90)) ||
  fail "job $B2: the master resumed after generation '${resumed}', expected $last_gen ... 89"
((max_workers >= 2)) || fail "the extra worker allocation $W never joined (at most $max_workers worker)"
wait_for 30 "job $W ends by itself" is_final "$W" || fail "job $W did not stop after the master's allocation ended"
grep -h "piezoid-workers" "$SH/piezoid-workers-$W.out" | sed 's/^/    /'
[[ $(job_state "$W") == COMPLETED ]] || fail "job $W: $(job_state "$W")"
say "B2: COMPLETED after $(job_field "$B2" RunTime), resumed after generation $resumed; $max_workers workers at most; job $W stopped by itself"
wait "${REF_PIDS[1]}" || fail "the reference run of long.json failed"
REF_PIDS=()
n_res=$(find "$PIEZOID_STATE/results" -mindepth 1 -maxdepth 1 -type d | wc -l)
((n_res == 1)) || fail "$n_res results in $PIEZOID_STATE/results: the resubmission started a new job"
same_result "$(find "$PIEZOID_STATE/results" -mindepth 1 -maxdepth 1 -type d)" "$TMP/ref-long"
say "slurm_test: passed"
