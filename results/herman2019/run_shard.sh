#!/bin/bash
# Run (or resume) shard K of 8 of the paper's grid into its own store, outside the
# repository (STORES, default /work/campaign), as this table's shards were made:
#     results/herman2019/run_shard.sh K > LOG 2>&1
# then  herman2019 record STORES/herman2019-sKof8.h5 --shard K/8 --log LOG
# A stop (SIGTERM or Ctrl-C to mpiexec) ends the run cleanly; the same command resumes it.
# bash's time reports the CPU of every rank (mpiexec waits for them).
K=$1
STORES=${STORES:-/work/campaign}
cd "$(dirname "$0")/../.."
TIMEFORMAT="[time] real %R s, user %U s, sys %S s (all ranks)"
time nice -n 5 mpiexec -n 3 sweep run configs/herman2019.toml \
    --store "$STORES/herman2019-s${K}of8.h5" --shard "${K}/8" --no-bar
