#!/usr/bin/env bash
# GNU parallel: 8 shards at once on one machine, 1 thread each (the mesh does not depend on the
# thread count). Rerunning the same command redoes only the frames that are missing.
set -euo pipefail
SIM=${1:-sim}
OUT=${2:-mesh}
N=8
mkdir -p logs
parallel --jobs "$N" --joblog splash-jobs.log \
    splash recon "$SIM/" --spacing 0.014 --cell r/2 --threads 1 --shard {}/"$N" \
        --skip-existing --log-format json -o "$OUT/" '2>' "logs/shard-{}.jsonl" \
    ::: $(seq 1 "$N")
# Alternatively one job per frame (the spacing must then be given):
#   parallel splash recon {} --spacing 0.014 --skip-existing -o "$OUT/" ::: "$SIM"/frame_*.ply
