#!/usr/bin/env bash
# The Slurm recipe (deploy/slurm) for real, on this one machine: installs Slurm and MUNGE
# from Debian's packages if they are missing, starts munged, slurmctld and slurmd with a
# minimal configuration for localhost (in a temporary directory, on ports of its own),
# submits a 4-task job array that renders the shards of the embedded Cornell box at 32x32
# on whatever Vulkan driver is present (lavapipe on a GPU-less machine) plus the
# dependent merge job, waits for them, and compares the merged image with an unsplit
# run (`cohort compare`: bit for bit, or within float summation order). Stops the
# daemons it started and exits non-zero on any failure. Needs root (apt-get, munged's
# key, daemons): it runs itself through sudo otherwise. $COHORT is the binary to test
# (default: a debug build, made here). CI runs it after the tests (.ci/run); it takes
# about 15 s once Slurm is installed.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)

fail() {
    echo "slurm smoke test: FAILED: $*" >&2
    exit 1
}
if [ "$(id -u)" != 0 ]; then
    command -v sudo >/dev/null || fail "needs root (it installs packages and starts daemons), and there is no sudo"
    exec sudo --preserve-env=COHORT,KEEP_SLURM_LOGS,PATH "$0" "$@"
fi

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    echo "slurm smoke test: installing slurm-wlm and munge"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

if [ -z "${COHORT:-}" ]; then
    cargo build --locked -p cohort-cli
    COHORT=$repo/target/debug/cohort
fi
export COHORT

work=$(mktemp -d /tmp/cohort-slurm.XXXXXX)
chmod 755 "$work"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$work/xdg}
mkdir -p "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"
host=$(hostname -s)
export SLURM_CONF=$work/slurm.conf
started_munged=""

cleanup() {
    set +e
    if [ -f "$work/slurmctld.pid" ]; then
        scontrol shutdown >/dev/null 2>&1
        sleep 2
    fi
    for pidfile in "$work/slurmd.pid" "$work/slurmctld.pid" $started_munged; do
        [ -f "$pidfile" ] && kill "$(cat "$pidfile")" 2>/dev/null
    done
    if [ "${KEEP_SLURM_LOGS:-}" = "" ]; then
        rm -rf "$work"
    else
        echo "slurm smoke test: logs in $work"
    fi
}
trap cleanup EXIT

# MUNGE authenticates Slurm's messages; the package made a key. Use a munged already
# running, else start one (as its own user, as munged requires).
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    install -d -o munge -g munge -m 755 /run/munge
    runuser -u munge -- /usr/sbin/munged
    started_munged=/run/munge/munged.pid
    for _ in $(seq 50); do
        munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break
        sleep 0.1
    done
    munge -n | unmunge >/dev/null || fail "munged does not answer"
fi

cat >"$SLURM_CONF" <<EOF
ClusterName=cohort-smoke
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=6917
SlurmdPort=6918
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SlurmdParameters=config_overrides
ReturnToService=2
MinJobAge=600
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=smoke Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
mkdir -p "$work/state" "$work/spool" "$work/out"

slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start (see $work/slurmctld.log)"
slurmd -f "$SLURM_CONF" || fail "slurmd did not start (see $work/slurmd.log)"
for _ in $(seq 60); do
    state=$(sinfo -h -N -o %T 2>/dev/null | head -1)
    [ "$state" = idle ] && break
    sleep 0.5
done
[ "$state" = idle ] || {
    cat "$work/slurmctld.log" "$work/slurmd.log" >&2 || true
    fail "the node is not idle (state: ${state:-none})"
}

render_args=(--scene cornell --width 32 --height 32 --paths 16 --integrator nee)
echo "slurm smoke test: submitting 4 shards and the merge"
submitted=$(deploy/slurm/submit.sh 4 "$work/out" "${render_args[@]}")
echo "$submitted"
array=$(echo "$submitted" | sed -n 's/^array job \([0-9]*\).*/\1/p')
merge=$(echo "$submitted" | sed -n 's/.*merge job \([0-9]*\).*/\1/p')
[ -n "$array" ] && [ -n "$merge" ] || fail "could not read the job ids"

# Wait for the merge job (which waits for the array) to leave the queue.
for _ in $(seq 600); do
    [ -z "$(squeue -h -j "$array,$merge" 2>/dev/null)" ] && break
    sleep 0.5
done
for job in "$array" "$merge"; do
    states=$(scontrol -o show job "$job" | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | sort -u)
    if [ "$states" != COMPLETED ]; then
        tail -n 20 "$work"/out/slurm-*.out >&2 || true
        fail "job $job ended ${states:-unknown}, not COMPLETED"
    fi
done
for k in 0 1 2 3; do
    grep -q "shard          $k/4" "$work/out/slurm-${array}_$k.out" || fail "task $k did not render shard $k/4"
done

"$COHORT" render "${render_args[@]}" --out "$work/whole.exr" --png "$work/whole.png" >/dev/null
"$COHORT" compare "$work/out/final.exr" "$work/whole.exr" || fail "the merged shards differ from the unsplit render"
echo "slurm smoke test: passed (4 shards through a Slurm job array, merged, match the unsplit render)"
