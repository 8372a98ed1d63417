#!/bin/sh
# A one-node Slurm cluster on 127.0.0.1 in a scratch folder (the recipe of docs/campaign.md; Debian's
# slurm-wlm and munge, as root, no systemd, no cgroups): its own munge key and socket, slurmctld and
# slurmd on ports 26817/26818, stopped by PID. For tests/campaign/slurm_test.sh and
# bench/bench_campaign.sh.
#   one_node_slurm.sh start DIR   # then SLURM_CONF=DIR/slurm.conf sbatch ...; fails with a message
#   one_node_slurm.sh stop DIR
set -eu
S=$2
fail() { echo "one_node_slurm.sh: $*" >&2; exit 1; }

if [ "$1" = stop ]; then
  for pid_file in "$S/slurmd.pid" "$S/slurmctld.pid" "$S/munge/munged.pid"; do
    [ -f "$pid_file" ] && kill "$(cat "$pid_file")" 2> /dev/null || true
  done
  sleep 1
  exit 0
fi
[ "$1" = start ] || fail "expected start or stop, got $1"

for program in /usr/sbin/munged /usr/sbin/slurmctld /usr/sbin/slurmd; do
  [ -x "$program" ] || fail "$program missing: install Debian's slurm-wlm and munge (apt-get install slurm-wlm munge)"
done
for program in sbatch sinfo; do
  command -v "$program" > /dev/null || fail "$program missing: install Debian's slurm-wlm"
done
[ "$(id -u)" = 0 ] || fail "run as root: slurmd starts the job array's tasks"

rm -rf "$S"
mkdir -p "$S/state" "$S/spool" "$S/munge"
chmod 700 "$S/munge"

# munge: its own key, socket and daemon in the scratch folder (not the system's).
dd if=/dev/urandom of="$S/munge/munge.key" bs=1 count=1024 2> /dev/null
chmod 400 "$S/munge/munge.key"
/usr/sbin/munged --force --key-file="$S/munge/munge.key" --socket="$S/munge/munge.socket" \
  --pid-file="$S/munge/munged.pid" --log-file="$S/munge/munged.log" --seed-file="$S/munge/munged.seed"
munge --socket="$S/munge/munge.socket" -n | unmunge --socket="$S/munge/munge.socket" | grep -q 'STATUS:.*Success' ||
  fail "munge does not work (see $S/munge/munged.log)"

HOST=$(hostname -s)
MEMORY=$(awk '/MemTotal/ { print int($2 / 1024 / 2) }' /proc/meminfo)
cat > "$S/slurm.conf" << CONF
ClusterName=csp
SlurmctldHost=$HOST(127.0.0.1)
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$S/munge/munge.socket
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$S/state
SlurmdSpoolDir=$S/spool
SlurmctldPidFile=$S/slurmctld.pid
SlurmdPidFile=$S/slurmd.pid
SlurmctldLogFile=$S/slurmctld.log
SlurmdLogFile=$S/slurmd.log
SlurmctldPort=26817
SlurmdPort=26818
MessageTimeout=5
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$MEMORY State=UNKNOWN
PartitionName=local Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$S/slurm.conf
/usr/sbin/slurmctld -c -f "$SLURM_CONF"
/usr/sbin/slurmd -f "$SLURM_CONF"
waited=0
until sinfo -h -o %T 2> /dev/null | grep -q idle; do
  waited=$((waited + 1))
  [ $waited -le 60 ] || fail "the node is not idle after 60 s (sinfo: $(sinfo 2>&1 | tr '\n' ' '); logs in $S)"
  sleep 1
done

