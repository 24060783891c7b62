# A throw-away Slurm cluster for the deployment tests (sourced after lib.sh): a private munged
# (its own key and socket), slurmctld and slurmd from Debian's packages started by hand (no
# systemd), config, state and logs in a temporary folder, found by clients through SLURM_CONF.
# /etc/slurm, /etc/munge and any system munged are left alone.
# shellcheck shell=bash

# slurm_init DIR: the cluster's folders below DIR (made readable for the munge user) and munged.
# Sets SL (Slurm), MU (munge), SH (the "shared storage" the jobs use).
slurm_init() {
  chmod 0755 "$1"
  SL=$1/slurm MU=$1/munge SH=$1/shared
  mkdir -p "$SL/state" "$SH"
  install -d -o munge -g munge -m 0755 "$MU"
  if command -v mungekey >/dev/null; then
    runuser -u munge -- mungekey --create --keyfile="$MU/munge.key" || fail "mungekey"
  else
    (umask 077 && dd if=/dev/urandom of="$MU/munge.key" bs=1024 count=1 status=none) &&
      chown munge:munge "$MU/munge.key"
  fi
  runuser -u munge -- munged --socket="$MU/munge.sock" --key-file="$MU/munge.key" \
    --log-file="$MU/munged.log" --pid-file="$MU/munged.pid" --seed-file="$MU/munged.seed" ||
    { show_logs "$MU/munged.log"; fail "munged"; }
  wait_for 10 "munged answers" bash -c "munge -n -S '$MU/munge.sock' | unmunge -S '$MU/munge.sock'" ||
    fail "munge"
}

# free_ports N: N distinct TCP ports the system hands out (sockets bound to port 0 together), for
# the Slurm daemons, whose configuration needs numbers; piezoid's own endpoints bind tcp://…:*.
free_ports() {
  python3 -c '
import socket, sys
socks = [socket.socket() for _ in range(int(sys.argv[1]))]
for s in socks: s.bind(("127.0.0.1", 0))
print(" ".join(str(s.getsockname()[1]) for s in socks))' "$1"
}

# slurm_conf CONTROLLER NODE_AND_PARTITION_LINES: writes $SL/slurm.conf and exports SLURM_CONF.
# No cgroups (proctrack/linuxproc, task/none), nodes may claim more CPUs than they have.
slurm_conf() {
  local ctld_port slurmd_port
  read -r ctld_port slurmd_port < <(free_ports 2) && [[ -n $slurmd_port ]] || fail "no free port"
  cat >"$SL/slurm.conf" <<EOF
ClusterName=pztest
SlurmctldHost=$1
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$MU/munge.sock
CredType=cred/munge
StateSaveLocation=$SL/state
SlurmdSpoolDir=$SL/spool-%n
SlurmctldPidFile=$SL/slurmctld.pid
SlurmdPidFile=$SL/slurmd-%n.pid
SlurmctldLogFile=$SL/slurmctld.log
SlurmdLogFile=$SL/slurmd-%n.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SlurmdParameters=config_overrides
ReturnToService=2
MailProg=/bin/true
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
KillWait=10
$2
EOF
  export SLURM_CONF=$SL/slurm.conf
}

# Slurm clients run through sl (a test on several network namespaces sets SL_PREFIX).
SL_PREFIX=()
sl() { "${SL_PREFIX[@]}" "$@"; }
# job_state JOBID: PENDING, RUNNING, COMPLETED, FAILED, ...; job_field JOBID FIELD.
job_state() { sl scontrol show job "$1" -o 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2; }
job_field() { sl scontrol show job "$1" -o 2>/dev/null | tr ' ' '\n' | sed -n "s/^$2=//p"; }
is_final() {
  case $(job_state "$1") in COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY) return 0 ;; esac
  return 1
}
nodes_idle() {  # nodes_idle N: N nodes, all idle
  local s
  s=$(sl sinfo -h -N -o %T 2>/dev/null)
  [[ $(grep -c . <<<"$s") -eq $1 && -z $(grep -v '^idle$' <<<"$s") ]]
}

# slurm_stop: cancels the jobs (bounded wait), then stops slurmctld, the slurmds, munged (in this
# order: slurmctld waits on RPCs to slurmds that are gone). For the EXIT trap.
slurm_stop() {
  local pid
  [[ -n ${SL:-} ]] || return 0
  if [[ -f $SL/slurm.conf && -s $SL/slurmctld.pid ]]; then
    sl scancel --quiet --user=root 2>/dev/null
    wait_for 20 "the jobs are gone" bash -c "[[ -z \$(${SL_PREFIX[*]} squeue -h 2>/dev/null) ]]"
  fi
  for pid in $(cat "$SL/slurmctld.pid" "$SL"/slurmd-*.pid "$MU/munged.pid" 2>/dev/null); do stop_pid "$pid" 10; done
}
