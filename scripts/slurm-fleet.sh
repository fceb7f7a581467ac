#!/usr/bin/env bash
# The fleet under a real scheduler: a single-node Slurm (Debian's slurm-wlm and munge) runs
# examples/calibrate/slurm-array.sh as an array job over a simulated 20-unit line, then the
# dependent collect job; the fleet page and fleet.json must equal those of the in-process
# `--units` run on the same line (the directory names, which differ by construction, aside).
#
#   sudo scripts/slurm-fleet.sh [TCOMP_BINARY]      # as root: it starts munged, slurmctld, slurmd
#
# Every wait is bounded (SLURM_FLEET_TIMEOUT seconds, default 900); the daemons this script
# started are stopped by their PIDs on exit, whatever happened. Called from .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
tcomp=${1:-$root/target/release/tcomp}
limit=${SLURM_FLEET_TIMEOUT:-900}
[[ -x $tcomp ]] || { echo "slurm-fleet: no tcomp binary at $tcomp" >&2; exit 1; }
for b in slurmctld slurmd sbatch squeue sacct munged; do
    command -v "$b" >/dev/null || { echo "slurm-fleet: $b missing (apt-get install slurm-wlm munge)" >&2; exit 1; }
done

work=$(mktemp -d /tmp/tcomp-slurm.XXXXXX)
chmod 755 "$work"
pids=()
# The daemons write their state as they stop (slurmctld saves its job state into the spool),
# so cleanup waits for each to exit (bounded, then SIGKILL) before it removes the directory;
# removing it while a daemon still writes fails with "Directory not empty". A leftover
# temporary directory is reported but does not fail the run.
cleanup() {
    local p all=() i
    for p in "${pids[@]}"; do all+=("$p"); done
    for p in "$work"/*.pid; do [[ -f $p ]] && all+=("$(cat "$p")"); done
    for p in "${all[@]}"; do kill "$p" 2>/dev/null || true; done
    for p in "${all[@]}"; do
        for ((i = 0; i < 100; i++)); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$p" 2>/dev/null || true
    done
    for ((i = 0; i < 5; i++)); do rm -rf "$work" 2>/dev/null && return 0; sleep 1; done
    echo "slurm-fleet: could not remove $work (left behind)" >&2
    return 0
}
trap cleanup EXIT

# munge: a key of its own, a socket in the work directory.
mkdir -p "$work/munge"
chmod 700 "$work/munge"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$work/munge/munge.key"
munged --key-file="$work/munge/munge.key" --socket="$work/munge/socket" \
    --pid-file="$work/munged.pid" --log-file="$work/munged.log" --seed-file="$work/munge/seed" --force
export MUNGE_SOCKET=$work/munge/socket

# A one-node cluster: this host, its cores and memory, no accounting, no cgroups.
host=$(hostname -s)
cpus=$(nproc)
mem=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 1024 ))
mkdir -p "$work/spool/ctld" "$work/spool/d" "$work/log"
cat > "$work/slurm.conf" <<EOF
ClusterName=tcomp-ci
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/socket
CredType=cred/munge
StateSaveLocation=$work/spool/ctld
SlurmdSpoolDir=$work/spool/d
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
SlurmctldPort=6817
SlurmdPort=6818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MpiDefault=none
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=ci Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$work/slurm.conf
start=$(date +%s)
t0=$start
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
# Bounded wait for the node to come up.
until sinfo -h -o %T 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; do
    if (( $(date +%s) - start > 60 )); then
        echo "slurm-fleet: the node did not come up in 60 s" >&2
        sinfo >&2 || true; tail -n 20 "$work"/log/*.log >&2 || true
        exit 1
    fi
    sleep 1
done
echo "slurm-fleet: single-node Slurm up on $host ($cpus CPUs) in $(( $(date +%s) - t0 )) s"

# The line, the in-process fleet, then the same under Slurm.
cd "$work"
timeout "$limit" "$tcomp" simulate --preset qma --units 20 --outliers 2 --out line --quiet
spec=$root/examples/calibrate/fleet.calibrate.toml
timeout "$limit" "$tcomp" calibrate "$spec" --units line --out inproc --quiet
t1=$(date +%s)
export TCOMP=$tcomp
job=$(sbatch --parsable --array=0-19 --output="$work/log/task-%A_%a.log" --chdir="$work" \
    "$root/examples/calibrate/slurm-array.sh" "$spec" line slurm)
collect=$(sbatch --parsable --dependency=afterok:"$job" --output="$work/log/collect-%j.log" \
    --chdir="$work" --wrap "$tcomp calibrate $spec --collect slurm --out slurm --quiet")
echo "slurm-fleet: array job $job (20 tasks), collect job $collect after it"
until [[ -z $(squeue -h -j "$job,$collect" 2>/dev/null) ]]; do
    if (( $(date +%s) - t1 > limit )); then
        echo "slurm-fleet: the jobs did not finish in $limit s" >&2
        squeue >&2 || true; scancel "$job" "$collect" 2>/dev/null || true
        exit 1
    fi
    sleep 2
done
if [[ ! -f slurm/fleet.json ]]; then
    echo "slurm-fleet: the collect job wrote no fleet.json" >&2
    tail -n 30 "$work"/log/*.log >&2 || true
    exit 1
fi
echo "slurm-fleet: Slurm jobs done in $(( $(date +%s) - t1 )) s"

# Equal, but for the directory names (`data`: the in-process run names the units' folder, the
# collect job the folder it collected) and the last bits of floating-point sums: a unit fitted in
# its own process and one fitted beside 19 others in one rayon pool add in another order
# (measured: 1-ulp differences). Numbers are compared to 1e-12 relative.
python3 - "$work/inproc" "$work/slurm" <<'PY'
import json, re, sys
a, b = sys.argv[1], sys.argv[2]
def close(x, y, path):
    if isinstance(x, dict) and isinstance(y, dict):
        if set(x) != set(y):
            sys.exit(f"slurm-fleet: fleet.json keys differ at {path}: {sorted(set(x) ^ set(y))}")
        for k in x:
            if k != "data":
                close(x[k], y[k], f"{path}.{k}")
    elif isinstance(x, list) and isinstance(y, list):
        if len(x) != len(y):
            sys.exit(f"slurm-fleet: fleet.json list lengths differ at {path}")
        for i, (u, v) in enumerate(zip(x, y)):
            close(u, v, f"{path}[{i}]")
    elif isinstance(x, (int, float)) and isinstance(y, (int, float)) and not isinstance(x, bool):
        if abs(x - y) > 1e-12 * max(abs(x), abs(y), 1e-300):
            sys.exit(f"slurm-fleet: fleet.json differs at {path}: {x} vs {y}")
    elif x != y:
        sys.exit(f"slurm-fleet: fleet.json differs at {path}: {x!r} vs {y!r}")
close(json.load(open(f"{a}/fleet.json")), json.load(open(f"{b}/fleet.json")), "$")
num = re.compile(r"-?\d+\.\d+(?:e-?\d+)?")
def page(d):
    t = open(f"{d}/fleet.html").read().replace(d.rsplit("/", 1)[1], "OUT")
    return num.sub(lambda m: "%.9g" % float(m.group()), t)
if page(a) != page(b):
    pa, pb = page(a).splitlines(), page(b).splitlines()
    bad = [i for i, (x, y) in enumerate(zip(pa, pb)) if x != y][:3]
    sys.exit(f"slurm-fleet: fleet.html differs (lines {bad}, of {len(pa)} and {len(pb)})")
print("slurm-fleet: fleet.json (to 1e-12) and fleet.html (to 9 digits) equal the in-process run's")
PY
echo "slurm-fleet: 20 units under Slurm, total $(( $(date +%s) - start )) s"
