#!/usr/bin/env bash
# Blender live mode's time per frame (tests/blender/bench_live.py) over runs, optionally against
# the add-on of another git revision with the same splash_sph package, so that the add-on's own
# change is what differs. Runs alternate (this, other, this, …); the table gives per settings
# group the median over runs of the mean end-to-end s/frame, Blender's side (wall and CPU) and
# the package's CPU.
#
#   bench/live.sh -n 3 --vs 4405cf0 ../shared/data/cbd-small 0.014
#   BPY_PYTHON=/path/venv/bin/python bench/live.sh ../shared/data/cbd-small 0.014
#   bench/live.sh --play 24 --vs HEAD ../shared/data/cbd-small 0.014
#   bench/live.sh --pin none ../shared/data/cbd-small 0.014
#
# --play FPS plays the frames as an imported particle sequence paced at FPS (bench_live.py
# --play): end to end is then the main thread's time per frame change, and the CPU column
# counts every thread (live mode's read-ahead included) and the idle wait.
#
# --pin CPUS runs Blender (or BPY_PYTHON) under `taskset -c CPUS` for both add-ons alike, its
# threads and the package's with it (default 0,1; "none": unpinned; exits 2 without taskset or
# with a CPU not available); the add-on's build is not pinned. The table's header line gives
# the CPU model, the CPUs available and the pinning.
#
# Environment: BLENDER (default blender), or BPY_PYTHON, a Python with the `bpy` module
# (`pip install "bpy==4.5.*"`). Builds the add-on with scripts/build-blender-addon (maturin).
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=bench/pin.sh
. bench/pin.sh
runs=1 vs="" play=() pin=0,1
usage="usage: bench/live.sh [-n RUNS] [--vs REV] [--play FPS] [--pin CPUS] PARTICLES SPACING"
while [ $# -gt 2 ]; do
    case "$1" in
        -n) runs=$2; shift 2 ;;
        --vs) vs=$2; shift 2 ;;
        --play) play=(--play "$2"); shift 2 ;;
        --pin) pin=$2; shift 2 ;;
        *) echo "$usage" >&2; exit 2 ;;
    esac
done
[ $# -eq 2 ] || { echo "$usage" >&2; exit 2; }
particles=$(realpath "$1") spacing=$2
pin_setup "$pin"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scripts/build-blender-addon "$work/this.zip" >/dev/null
names=(this)
if [ -n "$vs" ]; then
    # The other revision's add-on files with this build's package.
    mkdir -p "$work/other"
    (cd "$work/other" && unzip -q "$work/this.zip" && rm -f splash_blender/*.py)
    for f in $(git ls-tree --name-only "$vs" blender/splash_blender/ | grep '\.py$'); do
        git show "$vs:$f" >"$work/other/splash_blender/$(basename "$f")"
    done
    (cd "$work/other" && zip -qr "$work/other.zip" splash_blender)
    names+=(other)
fi
export BLENDER_USER_CONFIG="$work/config" BLENDER_USER_SCRIPTS="$work/scripts"
for run in $(seq "$runs"); do
    for name in "${names[@]}"; do
        rm -rf "$work/config" "$work/scripts"
        bench_args=(-- --addon "$work/$name.zip" --particles "$particles" --spacing "$spacing"
                    ${play[@]+"${play[@]}"})
        if [ -n "${BPY_PYTHON:-}" ]; then
            ${pinned[@]+"${pinned[@]}"} "$BPY_PYTHON" tests/blender/bench_live.py "${bench_args[@]}"
        else
            ${pinned[@]+"${pinned[@]}"} "${BLENDER:-blender}" -b --factory-startup --python tests/blender/bench_live.py \
                "${bench_args[@]}"
        fi 2>&1 | grep -E '^(Blender [0-9]|live )' | sed "s/^/$name run $run: /" | tee -a "$work/log"
    done
done
echo
echo "$particles, r = $spacing; add-ons: this${vs:+ and $vs}${play[1]:+; played at ${play[1]} fps}; $runs runs; $pin_note; $(date -u +%F)"
echo
python3 - "$work/log" <<'PY'
import re, statistics, sys
rows = {}
for line in open(sys.argv[1]):
    m = re.match(r"(\w+) run \d+: live (\w+) .*?mean ([\d.]+) s/frame.*?Blender's side ([\d.]+) s; "
                 r"CPU ([\d.]+) s \((?:package ([\d.]+), Blender's side ([\d.]+))?", line)
    if m:
        rows.setdefault((m[1], m[2]), []).append([float(x or "nan") for x in m.groups()[2:]])
print("| add-on | settings | runs | end to end s/frame | Blender's side | CPU | its CPU | "
      "package CPU |")
print("|---|---|---|---|---|---|---|---|")
for (name, mode), values in sorted(rows.items()):
    med = [statistics.median(c) for c in zip(*values)]
    print(f"| {name} | {mode} | {len(values)} | {med[0]:.3f} | {med[1]:.3f} | {med[2]:.3f} | "
          + " | ".join("–" if x != x else f"{x:.3f}" for x in med[4:2:-1]) + " |")
PY
