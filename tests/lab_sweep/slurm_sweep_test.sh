#!/usr/bin/env bash
# `./lab sweep --slurm` against a real Slurm (ctest -L slurm): a one-node cluster of Debian's
# munged, slurmctld and slurmd, started here with their own configuration, key, socket, ports and
# state under WORK_DIR (proctrack/linuxproc, task/none: no cgroups, no systemd), then
#   - bad input (unknown partition, malformed --time, --shards 0, a plan that does not parse,
#     sbatch missing from PATH) gives one `lab: error:` line, exit status 2, and submits nothing;
#   - a 4-shard array sweep and its merge job give the data set of one unsharded local run, row
#     for row (timing columns aside), and with --fit the model raylab fit makes of it;
#   - a shard killed with scancel mid-way makes the merge fail, write nothing and print the command
#     rerunning that shard; that command completes the data set, keeping the killed shard's rows.
# Every daemon it started is stopped by process id on exit, whatever happened (trap), after the
# jobs are cancelled; on failure the daemons' and jobs' logs are printed.
#
# Usage: slurm_sweep_test.sh RAYLAB_TOOL REPO_DIR WORK_DIR
set -euo pipefail
source "$(dirname "$0")/common.sh"
start_s=$(date +%s)
node=$(hostname -s)
conf=$work/etc/slurm.conf
munge_socket=$work/munge/run/munge.socket
daemon_pids=()  # name:pid, in start order

say() { echo "slurm-test [$(($(date +%s) - start_s)) s]: $*"; }

print_logs() {
  local f
  for f in "$work"/log/*.log "$work"/log/*.out "$work"/run*/runs.csv.shards/*.log; do
    [ -f "$f" ] || continue
    echo "----- $f (last 40 lines)"
    tail -n 40 "$f"
  done
}

fail() {
  echo "slurm-test: FAILED: $*" >&2
  print_logs >&2
  exit 1
}

# Polls COMMAND every 0.2 s until it succeeds; fails naming WHAT after SECONDS.
wait_for() {  # WHAT SECONDS COMMAND...
  local what=$1 deadline=$(($(date +%s) + $2))
  shift 2
  until "$@" >/dev/null 2>&1; do
    [ "$(date +%s)" -lt "$deadline" ] || fail "timed out waiting for $what"
    sleep 0.2
  done
}

# Stops a process we started: SIGTERM, up to 10 s, then SIGKILL; reaps it.
stop_pid() {  # NAME PID
  local i
  kill -0 "$2" 2>/dev/null || return 0
  kill -TERM "$2" 2>/dev/null || true
  for ((i = 0; i < 50; i++)); do
    kill -0 "$2" 2>/dev/null || break
    sleep 0.2
  done
  if kill -0 "$2" 2>/dev/null; then
    echo "slurm-test: $1 (pid $2) ignored SIGTERM; killing it" >&2
    kill -KILL "$2" 2>/dev/null || true
  fi
  wait "$2" 2>/dev/null || true
}

# On exit: stop the local reference sweep if it still runs, cancel the jobs, stop the daemons by pid
# (last started first), then end any process the daemons left (slurmstepd carries the marker of
# slurmd's environment, job processes our SLURM_CONF).
cleanup() {
  local status=$? entry i p
  trap - EXIT
  [ -z "${local_sweep:-}" ] || stop_pid "local sweep" "$local_sweep"
  if [ ${#daemon_pids[@]} -gt 0 ] && command -v scancel >/dev/null; then
    timeout 10 scancel --user="$(id -un)" >/dev/null 2>&1 || true
    for ((i = 0; i < 50; i++)); do
      [ -n "$(timeout 5 squeue -h 2>/dev/null)" ] || break
      sleep 0.2
    done
  fi
  for ((i = ${#daemon_pids[@]} - 1; i >= 0; i--)); do
    entry=${daemon_pids[$i]}
    stop_pid "${entry%%:*}" "${entry##*:}"
  done
  local -a environ
  local ours job
  for p in /proc/[0-9]*; do  # builtins only: a fork costs ~20 ms on a loaded VM
    p=${p#/proc/}
    [ "$p" != $$ ] || continue
    { mapfile -d '' -t environ <"/proc/$p/environ"; } 2>/dev/null || continue
    ours=0 job=0
    for entry in "${environ[@]}"; do
      case "$entry" in
        "RAYLAB_SLURM_TEST=$work") ours=1 job=1 ;;
        "SLURM_CONF=$conf") ours=1 ;;
        SLURM_JOB_ID=*) job=1 ;;
      esac
    done
    if [ "$ours$job" = 11 ]; then
      echo "slurm-test: ending leftover process $p ($(tr '\0' ' ' <"/proc/$p/cmdline" 2>/dev/null))" >&2
      kill -KILL "$p" 2>/dev/null || true
    fi
  done
  [ "$status" = 0 ] && say "passed; daemons stopped" || echo "slurm-test: daemons stopped" >&2
  exit "$status"
}
trap cleanup EXIT
trap 'exit 143' TERM INT

# Starts a daemon in the foreground of a background job, so that its pid is ours to stop.
start_daemon() {  # NAME COMMAND...
  local name=$1
  shift
  RAYLAB_SLURM_TEST=$work "$@" >"$work/log/$name.out" 2>&1 &
  daemon_pids+=("$name:$!")
}

for cmd in munged munge unmunge slurmctld slurmd sbatch scontrol squeue scancel sinfo; do
  command -v "$cmd" >/dev/null || fail "$cmd not installed (./lab installs slurmctld slurmd slurm-client munge)"
done

# ---- a one-node cluster under $work
rm -rf "$work"
mkdir -p "$work"/{etc,log,state,spool,munge/run} "$work/munge/key"
chmod 700 "$work/munge/key"
chmod 755 "$work/munge/run"  # munged wants its socket directory searchable, and writable by itself only
head -c 1024 /dev/urandom >"$work/munge/key/munge.key"
chmod 600 "$work/munge/key/munge.key"
read -r ctld_port slurmd_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')
cat >"$conf" <<EOF
# One node, this host; everything under $work.
ClusterName=raylabtest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$munge_socket
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/log/slurmctld.pid
SlurmdPidFile=$work/log/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
MailProg=/bin/true
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
KillWait=5
MessageTimeout=10
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=1024 State=UNKNOWN
PartitionName=raylab Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$conf

say "starting munged, slurmctld, slurmd (node $node, ports $ctld_port/$slurmd_port, under $work)"
start_daemon munged munged --foreground --socket="$munge_socket" --key-file="$work/munge/key/munge.key" \
  --pid-file="$work/log/munged.pid" --log-file="$work/log/munged.log" --seed-file="$work/munge/munged.seed"
wait_for "munged's socket" 10 test -S "$munge_socket"
munge -S "$munge_socket" -n | unmunge -S "$munge_socket" >/dev/null || fail "munge cannot decode its own credential"
start_daemon slurmctld slurmctld -D -c -f "$conf"
wait_for "slurmctld to answer" 30 bash -c 'scontrol ping | grep -q UP'
start_daemon slurmd slurmd -D -f "$conf" -N "$node"
wait_for "node $node to be idle" 30 bash -c "sinfo -h -n $node -o %t | grep -qx idle"
say "cluster up: $(sinfo -h -o '%P %a %D %t %N')"

# ---- the plan: 2 scenes x 4 structures x 4 ray sets = 32 cases; shard K of 4 gets ray set K, 8 cases,
# the small scene's first, so that a shard with a row has its larger structures still to build (a
# second or two): the window in which it is killed mid-way. With 20,000 triangles the faster builders
# finished a shard in about 0.5 s, and scancel, on a loaded machine, once arrived after it.
cd "$work"
cat >plan.json <<'EOF'
{"description": "slurm test: a few seconds per shard",
 "scenes": ["sphere:n=300", "sphere:n=80000"],
 "accels": ["bvh", "kdtree", "grid", "octree"],
 "rays": ["primary:1024", "shadow:512", "diffuse:512", "lines:512"]}
EOF

# The unsharded local run the merged data sets must equal, meanwhile.
"$tool" sweep --plan plan.json --out local.csv >"$work/log/local_sweep.out" 2>&1 &
local_sweep=$!

# ---- bad input: one error line, exit status 2, nothing submitted
expect_refused() {  # WHAT COMMAND...
  local what=$1 status=0 err
  shift
  err=$("$@" 2>&1 >/dev/null) || status=$?
  [ "$status" = 2 ] || fail "$what: exit status $status, expected 2 ($err)"
  [[ "$err" == "lab: error: "* && "$err" != *$'\n'* ]] ||
    fail "$what: expected one 'lab: error:' line, got: $err"
  say "refused $what: $err"
}
echo '{"scenes": ["sphere:n=10"], "accels": ["bvh"' >broken_plan.json
mkdir -p no-sbatch  # what ./lab needs before it looks for sbatch, and no sbatch
for cmd in bash env dirname realpath nproc; do ln -s "$(command -v "$cmd")" no-sbatch/; done
expect_refused "an unknown partition" "${lab[@]}" sweep --slurm plan.json --shards 4 --partition nosuch --out bad.csv
expect_refused "a malformed --time" "${lab[@]}" sweep --slurm plan.json --shards 4 --time 1:2 --out bad.csv
expect_refused "--shards 0" "${lab[@]}" sweep --slurm plan.json --shards 0 --out bad.csv
expect_refused "a plan that does not parse" "${lab[@]}" sweep --slurm broken_plan.json --shards 4 --out bad.csv
expect_refused "sbatch missing from PATH" env PATH="$work/no-sbatch" "${lab[@]}" sweep --slurm plan.json --out bad.csv
[ -z "$(squeue -h)" ] || fail "bad input submitted jobs: $(squeue -h)"
[ ! -e bad.csv.shards ] || fail "bad input left bad.csv.shards behind"
dry=$("${lab[@]}" sweep --slurm plan.json --shards 4 --partition raylab --time 00:10:00 --out dry.csv --dry-run)
grep -q '^#SBATCH --array=0-3$' <<<"$dry" && grep -q 'afterany' <<<"$dry" || fail "--dry-run printed: $dry"
[ -z "$(squeue -h)" ] && [ ! -e dry.csv.shards ] || fail "--dry-run submitted or wrote something"

job_state() {
  local record
  record=$(scontrol show job -o "$1" 2>/dev/null) || true
  [[ "$record" =~ JobState=([A-Z_]+) ]] && echo "${BASH_REMATCH[1]}"
}
# Waits until job $1 has ended; prints its state.
wait_for_job() {  # JOB SECONDS
  local deadline=$(($(date +%s) + $2)) state
  while :; do
    state=$(job_state "$1")
    case "$state" in
      COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY | PREEMPTED | BOOT_FAIL | DEADLINE)
        echo "$state"
        return ;;
    esac
    [ "$(date +%s)" -lt "$deadline" ] || fail "timed out waiting for job $1 (state ${state:-unknown}); queue: $(squeue -h)"
    sleep 0.3
  done
}
submitted_job() {  # WHICH ("array" or "merge") SUBMIT_OUTPUT
  sed -n "s/^lab: submitted $1 job \([0-9][0-9]*\) .*/\1/p" <<<"$2"
}
# ---- an array sweep of 4 shards, merged and fitted
mkdir run1
submit=$("${lab[@]}" sweep --slurm plan.json --shards 4 --partition raylab --time 00:10:00 --out run1/runs.csv \
  --fit --model run1/model.json) || fail "submission failed: $submit"
echo "$submit"
merge_job=$(submitted_job merge "$submit")
[ -n "$merge_job" ] || fail "no merge job in: $submit"
state=$(wait_for_job "$merge_job" 120)
wait "$local_sweep" || fail "the local sweep failed: $(tail -n 3 "$work/log/local_sweep.out")"
[ -f run1/runs.csv ] || fail "merge job $merge_job ended $state without a data set"
same_rows local.csv run1/runs.csv || fail "the merged array sweep differs from the local run"
# --fit: the merge job fitted the merged data set into the model, as raylab fit does by hand.
"$tool" fit --runs run1/runs.csv --out fit_by_hand.json >fit_by_hand.out 2>&1 ||
  fail "raylab fit of the merged data set failed: $(tail -n 1 fit_by_hand.out)"
[ "$state" = COMPLETED ] && [ -s run1/model.json ] || fail "merge job $merge_job ended $state, model: $(ls run1)"
families() { /usr/bin/python3 -c 'import json,sys; print(sorted(json.load(open(sys.argv[1]))["families"]))' "$1"; }
[ "$(families run1/model.json)" = "$(families fit_by_hand.json)" ] || fail "the merge job's model covers other families than the fit by hand"
fit_note="model fitted ($(families run1/model.json))"
grep -q '"how": "[^"]*slurm: array job [0-9]*, shards 0-3 of 4, merge job' run1/runs.csv.sweep.json || fail "the merge record does not say how it ran"
say "4 shards merged: $(($(wc -l <run1/runs.csv) - 1)) rows equal the local run's; $fit_note"

# ---- a shard killed mid-way: the merge reports it; the printed resubmission completes the data set
mkdir run2
submit=$("${lab[@]}" sweep --slurm plan.json --shards 4 --out run2/runs.csv) || fail "submission failed: $submit"
array_job=$(submitted_job array "$submit")
merge_job=$(submitted_job merge "$submit")
killed=""
deadline=$(($(date +%s) + 60))
while [ -z "$killed" ]; do
  for k in 0 1 2 3; do
    f=run2/runs.csv.shards/shard-$k-of-4.csv
    lines=()
    [ ! -f "$f" ] || mapfile -t lines <"$f"
    if [ ${#lines[@]} -ge 2 ]; then  # header and at least one row: running
      scancel "${array_job}_$k"
      killed=$k
      snapshot=$(cat "$f" && echo .)  # the rows at the kill, less a row being written
      snapshot=${snapshot%.}
      [[ "$snapshot" == *$'\n' ]] || snapshot=${snapshot%$'\n'*}$'\n'
      printf '%s' "$snapshot" | tail -n +2 >kept_rows.csv
      break
    fi
  done
  [ -n "$killed" ] || [ "$(date +%s)" -lt "$deadline" ] || fail "no shard wrote a row within 60 s"
  sleep 0.05
done
state=$(wait_for_job "$merge_job" 120)
[ "$state" = FAILED ] || fail "merge job $merge_job ended $state after shard $killed was cancelled"
[ "$(job_state "${array_job}_$killed")" = CANCELLED ] ||
  fail "shard $killed ended $(job_state "${array_job}_$killed") (it finished before scancel reached it)"
[ ! -e run2/runs.csv ] && [ ! -e run2/runs.csv.sweep.json ] || fail "an incomplete merge wrote a data set"
log=run2/runs.csv.shards/merge-$merge_job.log
grep -q "in shard $killed of 4" "$log" || fail "the merge log does not name shard $killed"
rerun=$(sed -n 's/^  \(.* --only [0-9,]*\)$/\1/p' "$log")
[[ "$rerun" == *" --only $killed" ]] || fail "no resubmission of shard $killed in $log"
say "shard $killed cancelled after $(grep -c '' kept_rows.csv) rows; the merge printed: $rerun"
submit=$(bash -c "$rerun") || fail "the resubmission failed: $submit"
echo "$submit"
merge_job=$(submitted_job merge "$submit")
state=$(wait_for_job "$merge_job" 120)
[ "$state" = COMPLETED ] || fail "the second merge job $merge_job ended $state"
same_rows local.csv run2/runs.csv || fail "the completed data set differs from the local run"
while IFS= read -r row; do
  grep -qxF -- "$row" run2/runs.csv || fail "a row shard $killed finished before its kill was lost: $row"
done <kept_rows.csv
say "resubmitted shard $killed resumed: $(($(wc -l <run2/runs.csv) - 1)) rows, the killed shard's rows kept"
