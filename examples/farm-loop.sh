#!/usr/bin/env bash
# One splash process per shard, one after another, on one machine: restartable at any time.
# Give the spacing (or --particle-radius) so that every process uses the same grid.
set -euo pipefail
SIM=${1:-sim}        # directory of frame_NNNN.ply files
OUT=${2:-mesh}       # meshes go to $OUT/frame_NNNN.obj
JOBS=4
for k in $(seq 1 "$JOBS"); do
    splash recon "$SIM/" --spacing 0.014 --cell r/2 --shard "$k/$JOBS" --skip-existing \
        -o "$OUT/" || echo "shard $k/$JOBS had failed frames; rerun this script to retry them" >&2
done
