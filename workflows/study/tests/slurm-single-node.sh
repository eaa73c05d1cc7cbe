#!/usr/bin/env bash
# A one-node Slurm on this machine, for the study workflow's test: munge, slurmctld and slurmd
# (configless: the job steps get the configuration from the controller), its files all under DIR,
# on the ports given. Needs root and Debian's slurmctld, slurmd, slurm-client and munge.
#   slurm-single-node.sh start DIR CTLD_PORT SLURMD_PORT   → prints the SLURM_CONF to use
#   slurm-single-node.sh stop DIR
set -euo pipefail
action="$1" dir="$2"
case "$action" in
start)
  ctld_port="$3" slurmd_port="$4"
  mkdir -p "$dir/state" "$dir/spool" "$dir/log"
  # munge: the key the package made; one daemon for the machine (started if none runs)
  if ! munge -n > /dev/null 2>&1; then
    mkdir -p /run/munge && chown munge:munge /run/munge
    runuser -u munge -- /usr/sbin/munged
    touch "$dir/started-munged"
  fi
  host=$(hostname -s)
  cpus=$(nproc)
  memory=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 * 3 / 4 ))
  cat > "$dir/slurm.conf" <<CONF
ClusterName=foveal-test
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
SlurmctldParameters=enable_configless
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/jobcomp.txt
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MinJobAge=3600
ReturnToService=2
MpiDefault=none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
  slurmctld -f "$dir/slurm.conf"
  for _ in $(seq 50); do SLURM_CONF="$dir/slurm.conf" scontrol ping 2> /dev/null | grep -q UP && break; sleep 0.2; done
  slurmd --conf-server "127.0.0.1:$ctld_port"
  for _ in $(seq 100); do
    SLURM_CONF="$dir/slurm.conf" sinfo -h -o %t 2> /dev/null | grep -q idle && { echo "$dir/slurm.conf"; exit 0; }
    sleep 0.2
  done
  echo "slurm-single-node.sh: the node did not come up (logs in $dir/log)" >&2
  exit 1
  ;;
stop)
  for daemon in slurmd slurmctld; do
    [ -f "$dir/$daemon.pid" ] && kill "$(cat "$dir/$daemon.pid")" 2> /dev/null || true
  done
  if [ -f "$dir/started-munged" ]; then pkill -u munge munged || true; fi
  ;;
*)
  echo "usage: slurm-single-node.sh start DIR CTLD_PORT SLURMD_PORT | stop DIR" >&2
  exit 2
  ;;
esac
