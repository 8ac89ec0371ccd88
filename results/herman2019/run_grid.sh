#!/bin/bash
# Run shards of the paper's grid one after another with run_shard.sh, starting none after
# a deadline (so that a session's end does not cut a shard whose store would be lost):
#     results/herman2019/run_grid.sh N DEADLINE K1 K2 ...   # DEADLINE: `date -d` text
# Each shard's log is LOGS/sKofN.log (LOGS default /work/campaign/logs); a shard already
# finished (its log has the run's summary and no stop) is skipped.
N=$1; DEADLINE=$(date -d "$2" +%s); shift 2
LOGS=${LOGS:-/work/campaign/logs}
HERE="$(cd "$(dirname "$0")" && pwd)"
mkdir -p "$LOGS"
for K in "$@"; do
    LOG="$LOGS/s${K}of${N}.log"
    if [ -f "$LOG" ] && grep -q "stored now" "$LOG" && ! grep -q "campaign stopped" "$LOG"; then
        echo "shard $K/$N: done before ($LOG)"; continue
    fi
    if [ "$(date +%s)" -ge "$DEADLINE" ]; then
        echo "shard $K/$N: not started, past the deadline $(date -d @"$DEADLINE")"; continue
    fi
    echo "shard $K/$N: start $(date -u +%FT%TZ)"
    "$HERE/run_shard.sh" "$K" "$N" >> "$LOG" 2>&1
    echo "shard $K/$N: exit $? $(date -u +%FT%TZ)"
done
