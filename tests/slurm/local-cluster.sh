#!/usr/bin/env bash
# A one-node Slurm cluster on localhost for tests: munged, slurmctld and slurmd started by hand (no
# systemd), every file in DIR, every port chosen free, so it runs as root in a container beside a
# real Slurm or another copy of itself.
#   tests/slurm/local-cluster.sh start DIR   writes DIR/slurm.conf, starts the daemons, waits until
#                                            the node is idle; prints "export SLURM_CONF=DIR/slurm.conf"
#   tests/slurm/local-cluster.sh stop DIR    stops the daemons it started (by the pid files in DIR)
# Exit status 77: the daemons cannot run here (not root, a binary missing, a daemon that does not come
# up); the reason is on stderr and in DIR/*.log.
set -euo pipefail
action=${1:-}
dir=${2:-}
[[ -n $dir && ($action == start || $action == stop) ]] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)

skip() { echo "local-cluster: cannot start Slurm here: $*" >&2; exit 77; }

stop() {
    # The jobs first: their steps (slurmstepd) outlive a stopped slurmd. Then slurmd (it reports to
    # slurmctld), munged last; only the processes whose pid files are here.
    if [[ -f $dir/slurm.conf && -f $dir/slurmctld.pid ]]; then
        SLURM_CONF=$dir/slurm.conf scancel --user="$(id -un)" 2>/dev/null || true
        for _ in $(seq 50); do
            [[ -z $(SLURM_CONF=$dir/slurm.conf squeue -h 2>/dev/null) ]] && break
            sleep 0.1
        done
    fi
    for daemon in slurmd slurmctld munged; do
        local pidfile=$dir/$daemon.pid
        [[ -f $pidfile ]] || continue
        local pid
        pid=$(cat "$pidfile")
        if [[ -n $pid ]] && kill -0 "$pid" 2>/dev/null; then
            kill "$pid" 2>/dev/null || true
            for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
            kill -9 "$pid" 2>/dev/null || true
        fi
        rm -f "$pidfile"
    done
}

free_port() {
    /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

if [[ $action == stop ]]; then
    stop
    exit 0
fi

((EUID == 0)) || skip "slurmd runs as root (this is uid $EUID)"
for tool in munged slurmctld slurmd sbatch squeue scontrol; do
    command -v "$tool" >/dev/null || [[ -x /usr/sbin/$tool ]] || skip "$tool is not installed (packages slurm-wlm, munge)"
done
export PATH=$PATH:/usr/sbin

mkdir -p "$dir/spool" "$dir/state" "$dir/munge"
chmod 700 "$dir/munge"
# munged insists on a key only its user can read.
head -c 1024 /dev/urandom >"$dir/munge/munge.key"
chmod 400 "$dir/munge/munge.key"
socket=$dir/munge/munge.socket
munged --force --key-file="$dir/munge/munge.key" --socket="$socket" --pid-file="$dir/munged.pid" \
    --log-file="$dir/munged.log" --seed-file="$dir/munge/munged.seed" >>"$dir/munged.log" 2>&1 \
    || skip "munged did not start (see $dir/munged.log)"

cpus=$(nproc)
ctld_port=$(free_port)
slurmd_port=$(free_port)
host=$(hostname -s)
cat >"$dir/slurm.conf" <<CONF
ClusterName=rastercheck-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
SwitchType=switch/none
SlurmdParameters=config_overrides
SchedulerParameters=defer_batch=0
MinJobAge=3600
InactiveLimit=0
KillWait=2
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$dir/slurm.conf
slurmctld -f "$SLURM_CONF" >>"$dir/slurmctld.log" 2>&1 || { stop; skip "slurmctld did not start (see $dir/slurmctld.log)"; }
slurmd -f "$SLURM_CONF" >>"$dir/slurmd.log" 2>&1 || { stop; skip "slurmd did not start (see $dir/slurmd.log)"; }
for _ in $(seq 150); do
    state=$(sinfo -h -N -o %t 2>/dev/null | head -1 || true)
    [[ $state == idle ]] && { echo "export SLURM_CONF=$SLURM_CONF"; exit 0; }
    sleep 0.2
done
stop
skip "the node did not become idle in 30 s (state '${state:-none}'; see $dir/slurmctld.log, $dir/slurmd.log)"
