#!/bin/bash
# Run shards of the paper's grid one after another with run_shard.sh, starting none after
# a deadline (so that a session's end does not cut a shard whose store would be lost):
#     results/herman2019/run_grid.sh N DEADLINE K1 K2 ...   # DEADLINE: `date -d` text
# CHECKOUT (default: this script's own checkout) is the checkout whose run_shard.sh, and so
# whose code, runs the shards: a worktree of the release tag, e.g. CHECKOUT=../release.
# CONFIG (passed to run_shard.sh; default configs/herman2019.toml) runs another campaign
# file; its logs then go to LOGS default /work/campaign/logs-<its name>, so that one
# campaign's finished shards are not taken for another's.
# The deadline is checked before each shard starts: give the session's end minus one
# shard's duration. Each run of shard K writes its own log, LOGS/sKofN.runM.log (LOGS
# default /work/campaign/logs), for `herman2019 record ... --log` in order; a shard whose
# latest run completed (its log has the summary and no stop) is skipped.
# Exit status 2 for a bad N, DEADLINE or K.
set -u
N=${1:-}; WHEN=${2:-}; shift 2 2>/dev/null || true
case "$N" in ''|*[!0-9]*) echo "run_grid.sh: N must be a positive integer, got '$N'" >&2; exit 2;; esac
DEADLINE=$(date -d "$WHEN" +%s 2>/dev/null) || { echo "run_grid.sh: DEADLINE '$WHEN' is not a date" >&2; exit 2; }
NAME=$(basename "${CONFIG:-configs/herman2019.toml}" .toml)
if [ "$NAME" = herman2019 ]; then LOGS=${LOGS:-/work/campaign/logs}; else LOGS=${LOGS:-/work/campaign/logs-$NAME}; fi
CHECKOUT="$(cd "${CHECKOUT:-$(dirname "$0")/../..}" && pwd)"
for K in "$@"; do
    case "$K" in ''|*[!0-9]*) echo "run_grid.sh: shard '$K' is not an integer" >&2; exit 2;; esac
    [ "$K" -lt "$N" ] || { echo "run_grid.sh: shard $K is not below N = $N" >&2; exit 2; }
done
mkdir -p "$LOGS"
for K in "$@"; do
    last=$(ls "$LOGS"/s"${K}"of"${N}".run*.log 2>/dev/null | sort -V | tail -1)
    if [ -n "$last" ] && grep -q "stored now" "$last" && ! grep -q "campaign stopped" "$last"; then
        echo "shard $K/$N: done before ($last)"; continue
    fi
    if [ "$(date +%s)" -ge "$DEADLINE" ]; then
        echo "shard $K/$N: not started, past the deadline $(date -d @"$DEADLINE")"; continue
    fi
    M=1
    while [ -e "$LOGS/s${K}of${N}.run${M}.log" ]; do M=$((M + 1)); done
    echo "shard $K/$N: run $M start $(date -u +%FT%TZ)"
    "$CHECKOUT/results/herman2019/run_shard.sh" "$K" "$N" > "$LOGS/s${K}of${N}.run${M}.log" 2>&1
    echo "shard $K/$N: run $M exit $? $(date -u +%FT%TZ)"
done
