#!/usr/bin/env bash
# `glassfusion batch --slurm --submit` on a real Slurm: a one-node cluster on loopback (munged,
# slurmctld and slurmd from Debian's munge and slurm-wlm, with their own ports, key, state and
# spool in WORK), an array of three captures (two small synthetic ones and a broken one), waited for
# with a bounded timeout; then `batch --collect` must report the two done (with their ATE and
# completeness gain) and the broken one failed. Every daemon started here is stopped on exit.
# Prints "SKIPPED: ..." and exits 0 only where the daemons cannot be installed or started.
#
# Usage: slurm_batch.sh GLASSFUSION WORK
set -u
GF=$1
WORK=$2
PIDS=()
cleanup() {
  for pid in "${PIDS[@]}"; do kill "$pid" 2>/dev/null; done
  sleep 1
  for pid in "${PIDS[@]}"; do kill -9 "$pid" 2>/dev/null; done
}
trap cleanup EXIT
skip() { echo "SKIPPED: $*"; exit 0; }
fail() { echo "FAILED: $*"; for f in "$WORK"/log/*.log "$WORK"/out/batch/slurm-*.out; do
  [ -f "$f" ] && { echo "--- $f"; tail -20 "$f"; }; done; exit 1; }
for program in munged slurmctld slurmd sbatch squeue sinfo; do
  command -v "$program" >/dev/null || skip "$program not installed (make deps installs slurm-wlm and munge)"
done
[ "$(id -u)" = 0 ] || skip "slurmd must run as root to start jobs"

rm -rf "$WORK"
mkdir -p "$WORK"/{munge,state,spool,log,caps/broken}
chmod 700 "$WORK/munge"
# Free ports near a base picked from the process id, so that parallel runs do not collide.
BASE=$((20000 + ($$ % 20000)))
dd if=/dev/urandom of="$WORK/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$WORK/munge/munge.key"
SOCKET="$WORK/munge/munge.socket"
munged --force --key-file="$WORK/munge/munge.key" --socket="$SOCKET" \
  --pid-file="$WORK/munge/munged.pid" --log-file="$WORK/log/munged.log" \
  --seed-file="$WORK/munge/munged.seed" 2>"$WORK/log/munged.err" || skip "munged did not start: $(cat "$WORK/log/munged.err")"
PIDS+=("$(cat "$WORK/munge/munged.pid")")

MEMORY_MB=$(awk '/MemAvailable/ {print int($2 / 1024 / 2)}' /proc/meminfo)
CPUS=$(nproc)
cat >"$WORK/slurm.conf" <<EOF
ClusterName=gftest
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$BASE
SlurmdPort=$((BASE + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$SOCKET
CredType=cred/munge
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/log/slurmctld.log
SlurmdLogFile=$WORK/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
MpiDefault=none
ReturnToService=2
NodeName=gfnode NodeAddr=127.0.0.1 NodeHostname=$(hostname) CPUs=$CPUS RealMemory=$MEMORY_MB State=UNKNOWN
PartitionName=gfq Nodes=gfnode Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$WORK/slurm.conf"
slurmctld -f "$SLURM_CONF" -c -i 2>"$WORK/log/slurmctld.err" || skip "slurmctld did not start: $(cat "$WORK/log/slurmctld.err")"
sleep 1
[ -f "$WORK/slurmctld.pid" ] && PIDS+=("$(cat "$WORK/slurmctld.pid")")
slurmd -f "$SLURM_CONF" -N gfnode 2>"$WORK/log/slurmd.err" || skip "slurmd did not start: $(cat "$WORK/log/slurmd.err")"
for _ in $(seq 1 30); do
  [ -f "$WORK/slurmd.pid" ] && break
  sleep 1
done
[ -f "$WORK/slurmd.pid" ] && PIDS+=("$(cat "$WORK/slurmd.pid")")
for _ in $(seq 1 60); do
  state=$(sinfo -h -o %T 2>/dev/null)
  [ "$state" = idle ] && break
  sleep 1
done
[ "$state" = idle ] || skip "the node did not come up (state '$state'): $(tail -3 "$WORK/log/slurmd.log" 2>/dev/null)"
echo "slurm: one-node cluster up on 127.0.0.1:$BASE"

for seed in 31 32; do
  "$GF" synth --scene glass-table --frames 8 --seed $seed --out "$WORK/caps/glass$seed" >/dev/null 2>&1 \
    || fail "synth failed"
done
echo "not a capture" >"$WORK/caps/broken/rgb.txt"
"$GF" batch "$WORK/caps" --out "$WORK/out" --slurm --submit --mem $((MEMORY_MB / 2))M \
  --cpus-per-task 1 --time 00:20:00 >"$WORK/submit.txt" 2>&1 || fail "batch --slurm --submit: $(cat "$WORK/submit.txt")"
cat "$WORK/submit.txt"
grep -q -- '--array=0-2' "$WORK/out/batch.sbatch" || fail "batch.sbatch has no 3-task array"
for _ in $(seq 1 600); do
  [ -z "$(squeue -h 2>/dev/null)" ] && break
  sleep 1
done
[ -z "$(squeue -h)" ] || fail "the array did not finish within 10 minutes: $(squeue)"
"$GF" batch --collect "$WORK/out" >"$WORK/collect.txt" 2>&1 || fail "batch --collect: $(cat "$WORK/collect.txt")"
cat "$WORK/collect.txt"
grep -q "3 captures: 2 done (0 of them earlier), 1 failed, 0 pending" "$WORK/collect.txt" || fail "unexpected summary"
for seed in 31 32; do
  line=$(grep "^glass$seed,done,8," "$WORK/out/summary.csv") || fail "glass$seed not done in summary.csv"
  ate=$(echo "$line" | cut -d, -f5)
  gain=$(echo "$line" | cut -d, -f8)
  awk -v a="$ate" -v g="$gain" 'BEGIN { exit !(a != "" && a < 0.01 && g > 0) }' \
    || fail "glass$seed: ATE '$ate' m, completeness gain '$gain'"
done
grep -q "^broken,failed," "$WORK/out/summary.csv" || fail "the broken capture is not reported failed"
ls "$WORK"/out/batch/slurm-*.out >/dev/null 2>&1 || fail "no Slurm task output"
echo "slurm batch ok"
rm -rf "$WORK/caps" "$WORK/out"
