#!/usr/bin/env bash
# A single-node SLURM on this machine (Debian 12's slurm-wlm, munge, slurmdbd with mariadb), for the CI test
# of the SLURM profile (tests/workflow/test_slurm_cluster.py). Run as root:
#   bash tests/slurm/cluster.sh COMMAND...
# installs the packages if missing, writes slurm.conf, slurmdbd.conf and a munge key under a temporary
# directory, starts munged, mariadbd, slurmdbd, slurmctld and slurmd, runs COMMAND with SLURM_CONF set, then
# stops every daemon by its PID (trap: whatever happened) and exits with COMMAND's status.
set -euo pipefail
[ "$(id -u)" -eq 0 ] || { echo "tests/slurm/cluster.sh: run as root (it starts the SLURM daemons)" >&2; exit 2; }
pkgs="slurmctld slurmd slurm-client munge slurmdbd mariadb-server libpmix2"
if ! dpkg -s $pkgs >/dev/null 2>&1; then
  apt-get update -q
  DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends $pkgs
fi
echo "tests/slurm/cluster.sh: packages ready after ${SECONDS} s"
T=$(mktemp -d /tmp/slurm-ci.XXXXXX)
chmod 755 "$T"
pids=()
wait_for() {   # wait_for WHAT COMMAND...: up to 30 s, else name WHAT and fail
  local what=$1; shift
  for _ in $(seq 150); do "$@" >/dev/null 2>&1 && return 0; sleep 0.2; done
  echo "tests/slurm/cluster.sh: $what did not come up (logs: $T/log)" >&2; tail -n 20 "$T"/log/*.log >&2; return 1
}
teardown() {
  for ((i=${#pids[@]}-1; i>=0; i--)); do kill "${pids[i]}" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
    kill -9 "$pid" 2>/dev/null || true
  done
  rm -rf "$T"
}
trap teardown EXIT
node=$(hostname -s)
cpus=2                                   # declared CPUs: 2 (the CI machine's cores; jobs are tiny)
mem=6000                                 # declared memory (MiB); the site overlay says the same
export SLURM_CONF="$T/slurm.conf"
# tmp (TmpFS): the PMIx step directories, private to this cluster. Job ids restart at 1 with each cluster, and a
# /tmp/spmix_appdir_0_<job>.0 left by an earlier one (a step killed before its clean-up) fails that step's launch.
mkdir -p "$T/state" "$T/spool" "$T/db" "$T/log" "$T/tmp"

# munge: its own key, on the default socket (SLURM's persistent connections do not read AuthInfo)
mkdir -p /run/munge
dd if=/dev/urandom of="$T/munge.key" bs=1024 count=1 status=none
chmod 400 "$T/munge.key"
munged --force --key-file "$T/munge.key" --socket /run/munge/munge.socket.2 --pid-file "$T/munged.pid" \
  --log-file "$T/log/munged.log" --seed-file "$T/munge.seed"
pids+=("$(cat "$T/munged.pid")")

# mariadb on a private socket and port
mariadb-install-db --no-defaults --datadir="$T/db" --user=root --auth-root-authentication-method=socket \
  >"$T/log/mariadb-install.log" 2>&1
mariadbd --no-defaults --datadir="$T/db" --user=root --socket="$T/mysql.sock" --port=33061 \
  --bind-address=127.0.0.1 --pid-file="$T/mariadb.pid" --log-error="$T/log/mariadb.log" &
pids+=("$!")
wait_for mariadbd test -S "$T/mysql.sock"
mariadb --no-defaults --socket="$T/mysql.sock" -u root -e \
  "CREATE USER 'slurm'@'127.0.0.1' IDENTIFIED BY 'ci'; GRANT ALL ON slurm_acct_db.* TO 'slurm'@'127.0.0.1';"

cat >"$T/slurmdbd.conf" <<CONF
AuthType=auth/munge
DbdHost=localhost
DbdPort=16819
SlurmUser=root
StorageType=accounting_storage/mysql
StorageHost=127.0.0.1
StoragePort=33061
StorageUser=slurm
StoragePass=ci
StorageLoc=slurm_acct_db
PidFile=$T/slurmdbd.pid
LogFile=$T/log/slurmdbd.log
CONF
chmod 600 "$T/slurmdbd.conf"

cat >"$SLURM_CONF" <<CONF
ClusterName=ci
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
TmpFS=$T/tmp
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/log/slurmctld.log
SlurmdLogFile=$T/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=localhost
AccountingStoragePort=16819
JobAcctGatherType=jobacct_gather/linux
JobAcctGatherFrequency=5
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=ci Nodes=$node Default=YES MaxTime=60 State=UP
CONF

slurmdbd
wait_for slurmdbd test -s "$T/slurmdbd.pid"
pids+=("$(cat "$T/slurmdbd.pid")")
wait_for "the cluster's accounting" sacctmgr -i add cluster ci
slurmctld
wait_for slurmctld test -s "$T/slurmctld.pid"
pids+=("$(cat "$T/slurmctld.pid")")
slurmd -N "$node"
wait_for slurmd test -s "$T/slurmd.pid"
pids+=("$(cat "$T/slurmd.pid")")
wait_for "an idle node" bash -c 'sinfo -h -o %t | grep -qx idle'
sinfo
echo "tests/slurm/cluster.sh: SLURM up after ${SECONDS} s"
set +e
"$@"
status=$?
set -e
if [ $status -ne 0 ]; then
  for f in slurmctld slurmd; do echo "--- tail of $f.log"; tail -n 40 "$T/log/$f.log"; done
fi
echo "tests/slurm/cluster.sh: done after ${SECONDS} s (status $status)"
exit $status
