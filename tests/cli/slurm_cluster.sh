#!/usr/bin/env bash
# A real single-node Slurm cluster on this machine, for integration tests that submit batch jobs.
#
# Everything lives under one directory DIR and is started by this script alone: a munged with its
# own freshly generated key and socket, a slurmctld and a slurmd reading DIR/slurm.conf. Nothing in
# /etc/slurm, /etc/munge, /run or /var is read or written, and system daemons (a munged or slurmd
# started by the packages' init scripts, if any) are neither used nor touched.
#
#   bash tests/cli/slurm_cluster.sh start DIR    start the cluster; on success prints, on stdout,
#                                                  lines to eval:  export SLURM_CONF=DIR/slurm.conf
#   bash tests/cli/slurm_cluster.sh status DIR   exit 0 and print the same lines if all three
#                                                  daemons run and the node is up; else exit 1
#   bash tests/cli/slurm_cluster.sh stop DIR     cancel the cluster's jobs, stop the daemons this
#                                                  script started (pids recorded in DIR/run), wait
#                                                  for them to exit; idempotent
#   bash tests/cli/slurm_cluster.sh wait DIR JOBID [TIMEOUT_S]
#                                                  poll (5 Hz) until every task of JOBID has ended;
#                                                  prints JobId/JobState/ExitCode per task; exit 0
#                                                  if all COMPLETED, 1 otherwise, 124 on timeout
#
# When the cluster cannot be started (not root, a package missing, a daemon dies, the node does not
# come up in 30 s), start stops what it started, prints one line "skipped: <reason>" on stderr and
# exits 77, which CTest and the test's caller can read as "skip".
#
# By hand:
#   d=$(mktemp -d) && eval "$(bash tests/cli/slurm_cluster.sh start $d)"
#   sbatch --parsable --array=0-3 --wrap 'hostname; sleep 1'; squeue; sinfo
#   bash tests/cli/slurm_cluster.sh stop $d
#
# Layout of DIR: slurm.conf, plugstack.conf (empty), env (the export lines), munge/ (key 0400,
# socket, seed, log), state/ (StateSaveLocation), spool/ (SlurmdSpoolDir), log/ (daemon logs and
# their stdout/stderr), run/ (the pids stop acts on: munged.pid, slurmctld.pid, slurmd.pid).
#
# Ports: SlurmctldPort and SlurmdPort are two free TCP ports chosen at each start, at random in
# 20000-59999 (a port is taken as free when nothing accepts a connection on 127.0.0.1), so that a
# system slurmctld on 6817 or two clusters of parallel tests do not collide. The node is called
# kg-node, reached at 127.0.0.1; the controller is "localhost". slurmctld schedules at its 1 s
# tick, so a job starts 0-1 s after it is submitted, after a CPU frees up or after its dependency is
# met; CPUs are the only consumable resource: an array whose tasks ask 1 CPU runs nproc at a time.
#
# Waiting for a job: use "wait" above (or poll "scontrol show job -o ID" the same way). sbatch
# --wait works but polls at 2, 10, 42, 74... s after submission; sacct does not work (no
# accounting); squeue drops a job once it has ended, so it cannot tell success from failure.
#
# Packages (Debian 12): slurmctld slurmd slurm-client munge (slurm-wlm is only the meta-package of
# the first three). Runs as root only: slurmd must be root to start jobs as their submitter.
set -uo pipefail
export PATH=$PATH:/usr/sbin:/sbin  # munged, slurmctld, slurmd live in /usr/sbin

readonly NODE=kg-node
readonly PARTITION=kg
readonly START_TIMEOUT=30  # seconds for the node to be idle
readonly STOP_TIMEOUT=15   # seconds for a daemon to exit after SIGTERM before SIGKILL

usage() {
  echo "usage: bash $0 start|stop|status DIR | wait DIR JOBID [TIMEOUT_S]" >&2
  exit 2
}

(($# >= 2)) || usage
cmd=$1
[[ -n $2 ]] || usage
dir=$(realpath -m -- "$2")
conf=$dir/slurm.conf
export SLURM_CONF=$conf

# --- pids -------------------------------------------------------------------------------------

# The pid recorded for daemon $1 if that process still runs and is ours: its command line names
# DIR (every daemon is started with a path under DIR), so a recycled pid is never taken for it.
live_pid() {
  local f=$dir/run/$1.pid pid
  [[ -r $f ]] || return 1
  { read -r pid <"$f"; } 2>/dev/null || return 1
  [[ $pid =~ ^[0-9]+$ ]] || return 1
  [[ -r /proc/$pid/cmdline ]] || return 1
  tr '\0' ' ' <"/proc/$pid/cmdline" 2>/dev/null | grep -qF -- "$dir/" || return 1
  # A zombie (exited, not yet reaped) no longer runs.
  [[ $(awk '{print $3}' "/proc/$pid/stat" 2>/dev/null) != Z ]] || return 1
  echo "$pid"
}

# Processes left by our slurmd when it could not end them itself (the controller was gone): its
# slurmstepd carry KG_SLURM_CLUSTER=DIR, the marker set on slurmd at start; the jobs' tasks carry
# SLURM_CONF=DIR/slurm.conf together with a SLURM_JOB_ID (the shell or test that submitted them
# has the first but not the second). Prints their pids.
marked_pids() {
  local e p
  for e in /proc/[0-9]*/environ; do
    p=${e#/proc/}
    p=${p%/environ}
    [[ $p == "$$" || $p == "$BASHPID" ]] && continue
    if grep -qzxF -- "KG_SLURM_CLUSTER=$dir" "$e" 2>/dev/null ||
       { grep -qzxF -- "SLURM_CONF=$conf" "$e" 2>/dev/null && grep -qz '^SLURM_JOB_ID=' "$e" 2>/dev/null; }; then
      echo "$p"
    fi
  done
}

# SIGTERM the daemon $1 if it runs, wait for it to go, SIGKILL it after STOP_TIMEOUT.
stop_daemon() {
  local name=$1 pid i
  pid=$(live_pid "$name") || {
    rm -f "$dir/run/$name.pid"
    return 0
  }
  kill -TERM "$pid" 2>/dev/null
  for ((i = 0; i < STOP_TIMEOUT * 10; ++i)); do
    live_pid "$name" >/dev/null || break
    sleep 0.1
  done
  if live_pid "$name" >/dev/null; then
    kill -KILL "$pid" 2>/dev/null
    sleep 0.2
  fi
  rm -f "$dir/run/$name.pid"
}

stop_cluster() {
  local i left
  # Jobs first, while the controller can still cancel them: slurmstepd outlives slurmd otherwise.
  if live_pid slurmctld >/dev/null && live_pid slurmd >/dev/null; then
    local jobs
    jobs=$(squeue -h -o %A 2>/dev/null | sort -u | tr '\n' ' ')
    if [[ -n ${jobs// /} ]]; then
      # shellcheck disable=SC2086  # a list of job ids
      scancel $jobs 2>/dev/null
      for ((i = 0; i < 100; ++i)); do
        [[ -z $(squeue -h -o %A 2>/dev/null) ]] && break
        sleep 0.1
      done
    fi
  fi
  stop_daemon slurmd
  stop_daemon slurmctld
  stop_daemon munged
  # Whatever slurmd left behind: jobs nobody cancelled, steps still finishing. Killed outright, as
  # slurmctld would have had them killed; ours by the markers only.
  for ((i = 0; i < 20; ++i)); do
    left=$(marked_pids)
    [[ -z $left ]] && break
    # shellcheck disable=SC2086  # a list of pids
    kill -KILL $left 2>/dev/null
    sleep 0.1
  done
  rm -f "$dir/env"
}

# --- start ------------------------------------------------------------------------------------

skip() {
  echo "skipped: $*" >&2
  stop_cluster
  exit 77
}

# The last meaningful line of a log, to say why a daemon died: a fatal one, else the last error
# (less the harmless complaints of the MPI plugins about a missing PMIx), else the last line.
last_log_line() {
  local f
  for f in "$@"; do
    [[ -s $f ]] && grep -i 'fatal' "$f" | tail -n 1 | grep . && return 0
  done
  for f in "$@"; do
    [[ -s $f ]] && grep -i 'error' "$f" | grep -Eiv 'pmix|mpi|MailProg' | tail -n 1 | grep . && return 0
  done
  for f in "$@"; do [[ -s $f ]] && tail -n 1 "$f" && return 0; done
  echo "no log"
}

port_in_use() { (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }

# Two distinct free ports, printed on one line.
free_ports() {
  local picked=() p tries
  for ((tries = 0; tries < 200 && ${#picked[@]} < 2; ++tries)); do
    p=$((20000 + (RANDOM * 32768 + RANDOM) % 40000))
    [[ " ${picked[*]} " == *" $p "* ]] && continue
    port_in_use "$p" || picked+=("$p")
  done
  ((${#picked[@]} == 2)) || return 1
  echo "${picked[@]}"
}

# The node's hardware line from slurmd -C (CPUs, sockets, cores, threads, RealMemory), so that the
# node registers without a mismatch; falls back to nproc and /proc/meminfo.
node_hardware() {
  local line
  line=$(slurmd -C 2>/dev/null | grep -m1 '^NodeName=')
  if [[ -n $line ]]; then
    line=${line#NodeName=* }
    echo "$line"
    return
  fi
  local mem
  mem=$(awk '/^MemTotal:/ {print int($2 / 1024)}' /proc/meminfo)
  echo "CPUs=$(nproc) RealMemory=$mem"
}

write_conf() {
  local ctld_port=$1 slurmd_port=$2
  cat >"$conf" <<EOF
# Generated by tests/cli/slurm_cluster.sh: a single-node cluster on 127.0.0.1, all state in
# $dir. Regenerated at each start.
ClusterName=kinegraph-test
SlurmctldHost=localhost
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.sock
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/state/slurmctld.pid
SlurmdPidFile=$dir/spool/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$dir/plugstack.conf
MailProg=/bin/true
# No cgroups in containers: processes tracked through /proc, no task binding, no accounting.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
# CPUs are the consumable: jobs asking one CPU each share the node.
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
# Scheduling as prompt as slurmctld allows: it acts on submissions and job ends at its 1 s tick
# (batch_sched_delay=0: at the very next tick), and the backfill pass, every second too, is what
# starts array tasks. A job thus starts 0-1 s after it is submitted or after resources free up.
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0,sched_interval=1,bf_interval=1
# A job whose dependency can never be met (afterok on a failed job) is cancelled, not left pending.
DependencyParameters=kill_invalid_depend
ReturnToService=2
InactiveLimit=0
KillWait=5
MinJobAge=300
SlurmctldTimeout=30
SlurmdTimeout=30
MessageTimeout=10
NodeName=$NODE NodeAddr=127.0.0.1 NodeHostname=localhost $(node_hardware) State=UNKNOWN
PartitionName=$PARTITION Nodes=$NODE Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
EOF
}

# Runs "$@" detached (own session, no terminal, output to log/$name.out) and records its pid.
launch() {
  local name=$1
  shift
  setsid "$@" </dev/null >>"$dir/log/$name.out" 2>&1 &
  echo $! >"$dir/run/$name.pid"
}

# Waits up to $2 seconds for "$1" (a command) to succeed while daemons $3... stay alive.
wait_for() {
  local test=$1 timeout=$2 i d
  shift 2
  for ((i = 0; i < timeout * 10; ++i)); do
    eval "$test" && return 0
    for d in "$@"; do
      live_pid "$d" >/dev/null ||
        skip "$d died at start: $(last_log_line "$dir/log/$d.log" "$dir/munge/$d.log" "$dir/log/$d.out")"
    done
    sleep 0.1
  done
  return 1
}

print_env() {
  echo "export SLURM_CONF=$conf"
}

node_idle() {
  local state
  state=$(sinfo -h -n "$NODE" -o %T 2>/dev/null) || return 1
  [[ $state == idle ]]
}

start_cluster() {
  [[ $(id -u) == 0 ]] || { echo "skipped: slurm_cluster.sh needs root (slurmd starts jobs as their submitter)" >&2; exit 77; }
  local c
  for c in munged munge unmunge slurmctld slurmd slurmstepd sbatch squeue sinfo scontrol scancel; do
    command -v "$c" >/dev/null ||
      { echo "skipped: $c not found (install: slurmctld slurmd slurm-client munge)" >&2; exit 77; }
  done

  # slurm.conf has no quoting: a path with blanks, '#' or '=' would be cut.
  [[ $dir =~ ^[A-Za-z0-9_./+-]+$ ]] ||
    { echo "skipped: DIR '$dir' must be a plain path (letters, digits, _ . / + -)" >&2; exit 77; }
  # A cluster already running in DIR is replaced: a start always gives a fresh one.
  stop_cluster
  mkdir -p "$dir"/{munge,state,spool,log,run} || skip "cannot create $dir"
  rm -rf "${dir:?}"/state/* "${dir:?}"/spool/*
  : >"$dir/plugstack.conf"

  # --- munge
  rm -f "$dir/munge/munge.key"
  dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none || skip "cannot write munge key"
  chmod 0400 "$dir/munge/munge.key"
  # --force: munged refuses a socket in a directory others cannot search (DIR inside a 0700 temp
  # dir); it warns and goes on with it, which is fine here since every client runs as root.
  # munged logs to --log-file only when it daemonizes itself; it writes its pid to run/ then.
  setsid munged --force \
    --socket="$dir/munge/munge.sock" --key-file="$dir/munge/munge.key" \
    --pid-file="$dir/run/munged.pid" --log-file="$dir/munge/munged.log" \
    --seed-file="$dir/munge/munged.seed" </dev/null >>"$dir/log/munged.out" 2>&1 ||
    skip "munged failed to start: $(last_log_line "$dir/munge/munged.log" "$dir/log/munged.out")"
  wait_for "munge -S '$dir/munge/munge.sock' -n 2>/dev/null | unmunge -S '$dir/munge/munge.sock' >/dev/null 2>&1" \
    10 munged || skip "munged did not answer on $dir/munge/munge.sock in 10 s"

  # --- slurm
  local ports ctld_port slurmd_port
  ports=$(free_ports) || skip "no free TCP port found for slurmctld and slurmd"
  read -r ctld_port slurmd_port <<<"$ports"
  write_conf "$ctld_port" "$slurmd_port" || skip "cannot write $conf"
  # KG_SLURM_CLUSTER marks the daemons and what slurmd spawns (slurmstepd), for stop.
  launch slurmctld env KG_SLURM_CLUSTER="$dir" slurmctld -D -c -f "$conf"
  wait_for "scontrol ping 2>/dev/null | grep -q 'is UP'" 15 munged slurmctld ||
    skip "slurmctld did not answer in 15 s: $(last_log_line "$dir/log/slurmctld.log" "$dir/log/slurmctld.out")"
  launch slurmd env KG_SLURM_CLUSTER="$dir" slurmd -D -N "$NODE" -f "$conf"
  wait_for node_idle "$START_TIMEOUT" munged slurmctld slurmd ||
    skip "node $NODE not idle after ${START_TIMEOUT} s (state: $(sinfo -h -n "$NODE" -o %T 2>&1 | head -n 1)): $(last_log_line "$dir/log/slurmd.log" "$dir/log/slurmctld.log")"

  print_env | tee "$dir/env"
}

# Polls until every record of job $1 (one per array task) has finished, at most $2 seconds; prints
# "JobId=... JobState=... ExitCode=..." per record; exit 0 if all COMPLETED, 1 if any other end,
# 124 on timeout. sbatch --wait is no substitute: it polls at 2, 10, 42, 74... s after submission.
wait_job() {
  local job=$1 timeout=${2:-600} out states
  [[ $job =~ ^[0-9]+(_[0-9]+)?$ ]] || { echo "wait: bad job id '$job'" >&2; exit 2; }
  [[ $timeout =~ ^[0-9]+$ ]] || { echo "wait: bad timeout '$timeout'" >&2; exit 2; }
  local end=$((SECONDS + timeout))
  while ((SECONDS < end)); do
    out=$(scontrol show job -o "$job" 2>&1) || { echo "wait: $out" >&2; exit 1; }
    states=$(grep -o 'JobState=[A-Z_]*' <<<"$out" | sort -u)
    if ! grep -qE 'JobState=(PENDING|RUNNING|CONFIGURING|COMPLETING|SUSPENDED|REQUEUED|RESIZING|SIGNALING|STAGE_OUT|RESV_DEL_HOLD|REQUEUE_FED|REQUEUE_HOLD|SPECIAL_EXIT|STOPPED)$' <<<"$states"; then
      sed -E 's/^(JobId=[0-9]+)( ArrayJobId=[0-9]+ ArrayTaskId=[0-9]+)?.*( JobState=[A-Z_]*).*( ExitCode=[0-9:]+).*/\1\2\3\4/' <<<"$out"
      [[ $states == JobState=COMPLETED ]]
      exit
    fi
    sleep 0.2
  done
  echo "wait: job $job not finished after $timeout s: $(tr '\n' ' ' <<<"$states")" >&2
  exit 124
}

case $cmd in
  start) start_cluster ;;
  stop) stop_cluster ;;
  status)
    for d in munged slurmctld slurmd; do
      live_pid "$d" >/dev/null || { echo "$d not running" >&2; exit 1; }
    done
    node_idle || [[ $(sinfo -h -n "$NODE" -o %T 2>/dev/null) =~ ^(mixed|allocated)$ ]] ||
      { echo "node $NODE not up" >&2; exit 1; }
    print_env
    ;;
  wait) (($# >= 3)) || usage; wait_job "$3" "${4:-600}" ;;
  *) usage ;;
esac
