#!/usr/bin/env bash
# End-to-end check of `surftrack bench robustness --slurm` on a real single-node Slurm.
#
# On a Debian machine where it may run as root, it
#   1. installs Slurm and munge from Debian's packages if they are missing
#      (slurm-wlm, munge);
#   2. writes a private single-node configuration (this machine is the controller and
#      the only compute node, every address 127.0.0.1; nothing under /etc/slurm is
#      touched) and starts munged (unless one already answers), slurmctld and slurmd;
#   3. runs a small robustness sweep unsharded, then writes its Slurm scripts with
#      `--slurm`, submits them (a job array of shards + a merge job depending on it) and
#      waits for both jobs (bounded);
#   4. checks that every array task ran as its own shard and that the merged table
#      equals the unsharded one, timings and memory aside;
#   5. stops the daemons it started.
#
# Usage: scripts/slurm/check.sh            (builds target/release/surftrack if missing)
# Environment: SURFTRACK=path/to/surftrack, WORK=dir (default: a new temp dir, kept for
# inspection), SPHERES/SEEDS/STEPS/SHARDS for the sweep (defaults 3/4/3/2),
# SLURM_WAIT_SECONDS (default 900).
# Exit status: 0 the check passed; 1 it failed (the reason is printed last).
set -euo pipefail
cd "$(dirname "$0")/../.."

SPHERES=${SPHERES:-3}
SEEDS=${SEEDS:-4}
STEPS=${STEPS:-3}
SHARDS=${SHARDS:-2}
WAIT=${SLURM_WAIT_SECONDS:-900}
SURFTRACK=${SURFTRACK:-$PWD/target/release/surftrack}
WORK=${WORK:-$(mktemp -d /tmp/surftrack-slurm.XXXXXX)}
mkdir -p "$WORK"
WORK=$(cd "$WORK" && pwd)

fail() { echo "slurm check FAILED: $*" >&2; exit 1; }
say() { echo "== $*"; }

# --- 1. packages -------------------------------------------------------------------
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
   || ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
  say "installing slurm-wlm and munge (Debian packages)"
  [ "$(id -u)" = 0 ] || fail "installing packages needs root"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi
if [ ! -x "$SURFTRACK" ]; then
  say "building surftrack (release)"
  cargo build --release --locked -p bench-harness --bin surftrack
fi
SURFTRACK=$(cd "$(dirname "$SURFTRACK")" && pwd)/$(basename "$SURFTRACK")

# --- 2. a private single-node cluster ----------------------------------------------
ETC=$WORK/etc VAR=$WORK/var
mkdir -p "$ETC" "$VAR/ctld" "$VAR/slurmd" "$VAR/log"
NODE=$(hostname -s)
CPUS=$(nproc)
MEM=$(( $(awk '/MemTotal/ {print int($2/1024)}' /proc/meminfo) * 9 / 10 ))
CTLD_PORT=${SLURMCTLD_PORT:-6817}
SLURMD_PORT=${SLURMD_PORT:-6818}
cat > "$ETC/slurm.conf" <<CONF
# Single-node Slurm for scripts/slurm/check.sh (written by it; safe to delete).
ClusterName=surftrack-check
SlurmctldHost=$NODE(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$VAR/ctld
SlurmdSpoolDir=$VAR/slurmd
SlurmctldPidFile=$VAR/slurmctld.pid
SlurmdPidFile=$VAR/slurmd.pid
SlurmctldLogFile=$VAR/log/slurmctld.log
SlurmdLogFile=$VAR/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
MinJobAge=3600
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=$MEM State=UNKNOWN
PartitionName=check Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$ETC/slurm.conf

STARTED_MUNGE=""
cleanup() {
  set +e
  pids=""
  for pidfile in "$VAR/slurmd.pid" "$VAR/slurmctld.pid"; do
    [ -s "$pidfile" ] && pids="$pids $(cat "$pidfile")"
  done
  [ -n "$pids" ] && kill $pids 2>/dev/null
  # Wait (at most 15 s) until they are gone, so nothing outlives the check.
  for _ in $(seq 30); do
    alive=""
    for pid in $pids; do kill -0 "$pid" 2>/dev/null && alive=yes; done
    [ -z "$alive" ] && break
    sleep 0.5
  done
  if [ -n "$STARTED_MUNGE" ] && [ -s /run/munge/munged.pid ]; then
    kill "$(cat /run/munge/munged.pid)" 2>/dev/null
  fi
}
trap cleanup EXIT

if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
  say "starting munged"
  [ -s /etc/munge/munge.key ] || { mungekey --create 2>/dev/null || dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 2>/dev/null; }
  chown munge:munge /etc/munge/munge.key && chmod 400 /etc/munge/munge.key
  mkdir -p /run/munge /var/log/munge /var/lib/munge
  chown munge:munge /run/munge /var/log/munge /var/lib/munge
  runuser -u munge -- /usr/sbin/munged
  STARTED_MUNGE=yes
  for _ in $(seq 50); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break; sleep 0.2; done
  munge -n | unmunge >/dev/null || fail "munged does not answer"
fi

say "starting slurmctld and slurmd (config $SLURM_CONF)"
/usr/sbin/slurmctld -f "$SLURM_CONF"
/usr/sbin/slurmd -f "$SLURM_CONF" -N "$NODE"
ready=""
for _ in $(seq 120); do
  state=$(sinfo -h -n "$NODE" -o %t 2>/dev/null || true)
  case "$state" in idle*|mix*|alloc*) ready=yes; break ;; esac
  sleep 0.5
done
[ -n "$ready" ] || { tail -n 20 "$VAR/log/slurmctld.log" "$VAR/log/slurmd.log" >&2; fail "node $NODE never became idle (state: ${state:-none})"; }
sinfo

# --- 3. the sweep, unsharded and through Slurm -------------------------------------
SWEEP=(--spheres "$SPHERES" --seeds "$SEEDS" --steps "$STEPS" --tracker grid,collision
       --timeout 600 --no-pictures --quiet)
say "unsharded reference: ${SWEEP[*]}"
"$SURFTRACK" bench robustness "${SWEEP[@]}" --out "$WORK/whole"

say "writing the Slurm scripts ($SHARDS shards) and submitting"
"$SURFTRACK" bench robustness "${SWEEP[@]}" --slurm "$WORK/slurm" --slurm-shards "$SHARDS" \
  --out "$WORK/sharded"
submitted=$(sh "$WORK/slurm/submit.sh")
echo "$submitted"
ids=$(echo "$submitted" | tail -n 1)
array=$(echo "$ids" | sed -n 's/^array=\([0-9]*\) merge=\([0-9]*\)$/\1/p')
merge=$(echo "$ids" | sed -n 's/^array=\([0-9]*\) merge=\([0-9]*\)$/\2/p')
[ -n "$array" ] && [ -n "$merge" ] || fail "cannot read the job ids from submit.sh"
# The merge job must wait for the array.
scontrol show job "$merge" | grep -q "Dependency=afterany:${array}" \
  || fail "merge job $merge does not depend on array job $array"

deadline=$(( $(date +%s) + WAIT ))
while [ -n "$(squeue -h -j "$array,$merge" 2>/dev/null)" ]; do
  [ "$(date +%s)" -lt "$deadline" ] || { squeue; fail "jobs still queued or running after ${WAIT}s"; }
  sleep 2
done

# --- 4. checks ---------------------------------------------------------------------
for id in "$merge"; do
  scontrol show job "$id" | grep -q "JobState=COMPLETED" \
    || { scontrol show job "$id" >&2; cat "$WORK"/slurm/logs/merge-*.log >&2 || true; fail "merge job $id did not complete"; }
done
for ((i = 0; i < SHARDS; i++)); do
  scontrol show job "${array}_$i" | grep -q "JobState=COMPLETED" \
    || { cat "$WORK/slurm/logs/shard-$i.log" >&2 || true; fail "array task $i did not complete"; }
  [ -f "$WORK/sharded/shard-$i/robustness.json" ] || fail "shard $i wrote no record"
done
say "comparing the merged table with the unsharded one (timings and memory aside)"
python3 - "$WORK/whole/robustness.json" "$WORK/sharded/robustness.json" "$SHARDS" "$WORK/sharded" <<'PY'
import json, sys
whole_path, merged_path, shards, sharded = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
TIMES = {"wall_seconds", "step_seconds", "stage_seconds", "mean_seconds", "median_seconds",
         "max_seconds", "mean_stage_seconds", "peak_rss_mib", "mib_per_million_triangles",
         "max_peak_rss_mib", "max_mib_per_million_triangles"}
def strip(v):
    if isinstance(v, dict):
        out = {k: strip(x) for k, x in v.items() if k not in TIMES}
        if "reason" in out and "message" in out:
            out.pop("message")  # names the run directory
        return out
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v
whole = json.load(open(whole_path))
merged = json.load(open(merged_path))
for i in range(shards):
    shard = json.load(open(f"{sharded}/shard-{i}/robustness.json"))
    assert shard["config"]["shard"] == [i, shards], (i, shard["config"]["shard"])
a, b = strip(whole), strip(merged)
if a != b:
    print("whole :", json.dumps(a, sort_keys=True)[:2000])
    print("merged:", json.dumps(b, sort_keys=True)[:2000])
    sys.exit("the merged table differs from the unsharded run")
runs = merged["runs"]
print(f"{len(runs)} runs equal; successes:",
      {s["tracker"]: f'{s["successes"]}/{s["runs"]}' for s in merged["summary"]})
PY
"$SURFTRACK" bench merge "$WORK/sharded" --out "$WORK/remerged" | head -n 6
echo "slurm check passed (work dir: $WORK)"
