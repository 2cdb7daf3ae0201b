#!/usr/bin/env bash
# Starts NPROC processes of a data-parallel job on this machine with the
# environment variables torchrun sets (RANK, WORLD_SIZE, LOCAL_RANK,
# LOCAL_WORLD_SIZE, MASTER_ADDR, MASTER_PORT), waits for them, and ends the
# others as soon as one fails. Ctrl-C (SIGINT or SIGTERM to this script)
# reaches every process once; they stop together at the same step with a checkpoint.
#
#   scripts/launch.sh NPROC COMMAND...        e.g.
#   scripts/launch.sh 2 build/apps/flowplan/flowplan train --config configs/particle_cross.yaml train.data_parts=2
#
# Across machines, run it once per machine with NNODES, NODE_RANK and
# MASTER_ADDR (the first machine's address) set; MASTER_PORT defaults to 29500.
set -uo pipefail

if [ $# -lt 2 ] || ! [[ "$1" =~ ^[1-9][0-9]*$ ]]; then
  echo "usage: $0 NPROC COMMAND..." >&2
  exit 2
fi
nproc=$1
shift
nnodes=${NNODES:-1}
node_rank=${NODE_RANK:-0}
export MASTER_ADDR=${MASTER_ADDR:-127.0.0.1}
export MASTER_PORT=${MASTER_PORT:-29500}
export WORLD_SIZE=$((nproc * nnodes))
export LOCAL_WORLD_SIZE=$nproc

# Each process in its own process group (job control): a Ctrl-C at the
# terminal reaches this script alone, which passes exactly one SIGINT on (a
# second one would make flowplan quit without its checkpoint).
set -m
pids=()
trap 'kill -INT "${pids[@]}" 2>/dev/null' INT TERM
for ((local = 0; local < nproc; local++)); do
  RANK=$((node_rank * nproc + local)) LOCAL_RANK=$local "$@" &
  pids+=($!)
done

status=0
live=("${pids[@]}")
while [ ${#live[@]} -gt 0 ]; do
  finished=""
  wait -n -p finished "${live[@]}"
  code=$?
  [ -z "${finished:-}" ] && continue  # a trapped signal interrupted the wait; keep waiting
  next=()
  for pid in "${live[@]}"; do [ "$pid" != "$finished" ] && next+=("$pid"); done
  live=("${next[@]}")
  if [ "$code" -ne 0 ] && [ "$status" -eq 0 ]; then
    status=$code
    echo "launch.sh: process $finished exited with $code; stopping the others" >&2
    [ ${#live[@]} -gt 0 ] && kill -TERM "${live[@]}" 2>/dev/null
  fi
done
exit "$status"
