#!/bin/bash
# Run (or resume) shard K of N of the paper's grid into its own store, outside the
# repository (STORES, default /work/campaign), with the code of the checkout this script
# is in (its floewave, sweep and herman2019 come first on PYTHONPATH, so a release
# worktree runs its own tagged code whatever else is installed):
#     results/herman2019/run_shard.sh K N > LOG 2>&1
# then, from any checkout:
#     herman2019 record STORES/herman2019-sKofN.h5 --shard K/N --log LOG
# CONFIG (default configs/herman2019.toml, relative to the checkout) runs another campaign
# file the same way, into STORES/<its name>-sKofN.h5 (e.g. configs/herman2019_lx.toml).
# Refuses (exit 2) when the checkout's tracked files differ from its commit: a shipped
# run records one commit and git_dirty false. A stop (SIGTERM or Ctrl-C to mpiexec) ends
# the run cleanly; the same command resumes it. bash's time reports the CPU of every rank
# (mpiexec waits for them).
K=${1:-}; N=${2:-}
for v in "$K" "$N"; do
    case "$v" in *[!0-9]*|'') echo "run_shard.sh: give K and N, non-negative integers (K < N)" >&2; exit 2;; esac
done
[ "$K" -lt "$N" ] || { echo "run_shard.sh: K = $K is not below N = $N" >&2; exit 2; }
STORES=${STORES:-/work/campaign}
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
CONFIG=${CONFIG:-configs/herman2019.toml}
[ -f "$ROOT/$CONFIG" ] || { echo "run_shard.sh: CONFIG $CONFIG: no such file in $ROOT" >&2; exit 2; }
NAME=$(basename "$CONFIG" .toml)
cd "$ROOT"
if ! status=$(git status --porcelain --untracked-files=no); then
    echo "run_shard.sh: $ROOT: git status failed" >&2
    exit 2
fi
if [ -n "$status" ]; then
    echo "run_shard.sh: $ROOT has uncommitted changes to tracked files; commit them first" >&2
    exit 2
fi
mkdir -p "$STORES"
export PYTHONPATH="$ROOT${PYTHONPATH:+:$PYTHONPATH}"
TIMEFORMAT="[time] real %R s, user %U s, sys %S s (all ranks)"
time nice -n 5 mpiexec -n 3 python -m sweep run "$CONFIG" \
    --store "$STORES/${NAME}-s${K}of${N}.h5" --shard "${K}/${N}" --no-bar
