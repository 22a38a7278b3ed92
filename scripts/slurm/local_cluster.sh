#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for as long as a command runs: munged, slurmctld
# and slurmd from Debian's packages (munge, slurmctld, slurmd, slurm-client), started in the
# foreground of this script with a private configuration and state under DIR, and stopped by
# their PIDs when the command ends. No init system is needed or touched.
#
#   scripts/slurm/local_cluster.sh DIR COMMAND [ARGS...]
#
# COMMAND runs with SLURM_CONF set to DIR/slurm.conf, so that sbatch, squeue, scontrol and
# scripts/slurm/sweep.sh talk to this cluster. Run as root (the daemons run as root here, with
# proctrack/linuxproc and task/none: no cgroups). The exit status is COMMAND's.
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 DIR COMMAND [ARGS...]" >&2; exit 2; }
[ "$(id -u)" -eq 0 ] || { echo "$0: run as root (it starts munged, slurmctld and slurmd)" >&2; exit 2; }
for tool in munged slurmctld slurmd sbatch sinfo; do
  command -v $tool >/dev/null || {
    echo "$0: $tool is missing: apt-get install munge slurmctld slurmd slurm-client" >&2
    exit 2
  }
done
mkdir -p "$1"
DIR="$(cd "$1" && pwd)"
shift
mkdir -p "$DIR"/{munge,state,spool,log}
chmod 755 "$DIR/munge"  # the socket's folder: every user may reach it

# A key of its own, so that nothing of the machine's munge is read or changed.
[ -s "$DIR/munge/munge.key" ] || { dd if=/dev/urandom of="$DIR/munge/munge.key" bs=1024 count=1 status=none; }
chmod 400 "$DIR/munge/munge.key"

# Ports that nothing listens on yet.
free_port() {
  local port
  for port in $(seq "$1" $(($1 + 200))); do
    if ! (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then echo "$port"; return; fi
  done
  echo "$0: no free port from $1" >&2
  exit 1
}
ctld_port=$(free_port 16817)
slurmd_port=$(free_port $((ctld_port + 1)))
node=$(hostname -s)
cpus=$(nproc)
cat >"$DIR/slurm.conf" <<EOF
ClusterName=nbv-local
SlurmctldHost=$node
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$DIR/munge/munge.socket
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/slurmctld.pid
SlurmdPidFile=$DIR/slurmd.pid
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
MinJobAge=600
NodeName=$node CPUs=$cpus State=UNKNOWN
PartitionName=local Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$DIR/slurm.conf"

pids=()
stop() {
  local pid
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
}
trap stop EXIT

munged --foreground --force --socket="$DIR/munge/munge.socket" --key-file="$DIR/munge/munge.key" \
  --pid-file="$DIR/munge/munged.pid" --log-file="$DIR/log/munged.log" --seed-file="$DIR/munge/munged.seed" \
  >>"$DIR/log/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 100); do [ -S "$DIR/munge/munge.socket" ] && break; sleep 0.1; done
[ -S "$DIR/munge/munge.socket" ] || { echo "$0: munged did not start: $(tail -5 "$DIR/log/munged.out")" >&2; exit 1; }
slurmctld -D -i -f "$SLURM_CONF" >>"$DIR/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" >>"$DIR/log/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 300); do
  state=$(sinfo -h -N -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 0.1
done
if [ "$state" != idle ]; then
  echo "$0: the node is '${state:-not answering}', not idle, after 30 s:" >&2
  tail -5 "$DIR/log/slurmctld.log" "$DIR/log/slurmd.log" >&2 || true
  exit 1
fi
echo "local Slurm cluster: node $node ($cpus CPUs), slurmctld on port $ctld_port, SLURM_CONF=$SLURM_CONF"
set +e
"$@"
status=$?
set -e
exit $status
