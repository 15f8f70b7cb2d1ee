#!/usr/bin/env bash
# End-to-end test of `gapflow slurm` on a real, one-node Slurm started here from Debian's
# packages (slurm-wlm, munge), as root, from a generated slurm.conf in a temporary folder:
# its own munged (own key and socket), slurmctld and slurmd on unusual ports, nothing in
# /etc touched. It submits the tiny study as a job array of 3 tasks plus the dependent
# merge-and-report job, waits, and checks that the merged store equals a local run of the
# same study run by run (`gapflow compare`). ctest `slurm_study` (label slow).
#   scripts/slurm_local.sh [path/to/gapflow]
# Exit 0 passed, 1 failed, 77 skipped (not root, or Slurm/munge not installed).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
gapflow="$(readlink -f "${1:-$here/build/app/gapflow}")"
study="$here/studies/examples/tiny.toml"
tasks=3

[ "$(id -u)" -eq 0 ] || { echo "skipped: starts Slurm daemons, so needs root"; exit 77; }
for b in munged munge slurmctld slurmd sbatch squeue sinfo; do
  command -v "$b" >/dev/null || [ -x "/usr/sbin/$b" ] || { echo "skipped: no $b (apt-get install slurm-wlm munge)"; exit 77; }
done
PATH="$PATH:/usr/sbin"

tmp="$(mktemp -d /tmp/gapflow-slurm.XXXXXX)"
chmod 755 "$tmp"
pids=()
cleanup() {
  local rc=$?
  [ -n "${SLURM_CONF:-}" ] && { scancel --quiet -u root 2>/dev/null || true; }
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do  # they write their state on the way out
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
  done
  if [ $rc -ne 0 ]; then
    for log in "$tmp"/*.log "$tmp"/work/results/tiny/slurm/logs/*.log; do
      [ -f "$log" ] && { echo "---- $log"; tail -n 20 "$log"; }
    done
  fi
  rm -rf "$tmp"
}
trap cleanup EXIT
wait_for_pid_file() {  # daemons write their pid file once started
  for _ in $(seq 100); do [ -s "$1" ] && { cat "$1"; return 0; }; sleep 0.1; done
  echo "FAIL: no $1" >&2; return 1
}

# munge: a key of our own, a socket of our own (another munged on this machine is left alone).
mkdir -m 755 "$tmp/munge"
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1k count=1 status=none
chmod 600 "$tmp/munge/munge.key"
munged --force -S "$tmp/munge/munge.sock" --key-file="$tmp/munge/munge.key" --log-file="$tmp/munged.log" \
  --pid-file="$tmp/munge/munged.pid" --seed-file="$tmp/munge/munged.seed"
pids+=("$(wait_for_pid_file "$tmp/munge/munged.pid")")

# Slurm: one node (this machine), one partition, no accounting, no cgroups.
host="$(hostname -s)"
base_port=$((20000 + RANDOM % 20000))
mkdir -p "$tmp/state" "$tmp/spool"
cat >"$tmp/slurm.conf" <<CONF
ClusterName=gapflowlocal
SlurmctldHost=$host
SlurmctldPort=$base_port
SlurmdPort=$((base_port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge/munge.sock
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$tmp/slurm.conf"
slurmctld -f "$SLURM_CONF"
pids+=("$(wait_for_pid_file "$tmp/slurmctld.pid")")
slurmd -f "$SLURM_CONF"
pids+=("$(wait_for_pid_file "$tmp/slurmd.pid")")
for _ in $(seq 60); do
  grep -qE '^idle' <<< "$(sinfo -h -o %T 2>/dev/null)" && break
  sleep 1
done
grep -qE '^idle' <<< "$(sinfo -h -o %T)" || { echo "FAIL: the node did not come up"; sinfo; exit 1; }
echo "one-node Slurm up: $(sinfo -h -o '%P %D %T %c')"

# The study, as a job array of $tasks shares plus the dependent merge-and-report job.
mkdir "$tmp/work" && cd "$tmp/work"
"$gapflow" slurm "$study" --array-size "$tasks" --time 00:10:00
sh results/tiny/slurm/submit.sh
for _ in $(seq 300); do
  [ -z "$(squeue -h -o %i)" ] && break
  sleep 1
done
[ -z "$(squeue -h -o %i)" ] || { echo "FAIL: jobs still queued after 300 s"; squeue; exit 1; }
echo "---- merge job log"; cat results/tiny/slurm/logs/merge.log
shares=$(ls results/tiny/slurm/logs/share-*.log | wc -l)
[ "$shares" -eq "$tasks" ] || { echo "FAIL: $shares share logs, expected $tasks"; exit 1; }
grep -q "plan: 12 jobs, 12 stored, 0 missing" results/tiny/slurm/logs/merge.log || { echo "FAIL: merge incomplete"; exit 1; }
[ -f results/tiny/report.md ] || { echo "FAIL: no report"; exit 1; }
"$gapflow" export results/tiny/runs.sqlite --table provenance | tail -n +2 | cut -d, -f2 | sort | uniq -c

# The same study run locally: identical run by run.
"$gapflow" study "$study" --db "$tmp/local.sqlite" --jobs 2 2>/dev/null
"$gapflow" compare "$tmp/local.sqlite" results/tiny/runs.sqlite
echo "PASS: Slurm array of $tasks shares + merge == local run"
