#!/usr/bin/env bash
# The Python package in process against pysplashsurf's reconstruction_pipeline on one frame:
# wall time and the memory each call takes above the loaded positions (bench/inprocess.py, a
# fresh process per run), with the same parameters (density, support 2r, iso 0.6, cell r/2,
# raw mesh) and the same triangles. Runs alternate (splash, pysplashsurf, splash, …); the table
# gives medians and the median of the per-pair ratios. Installs nothing.
#
#   bench/python.sh -n 5 ../shared/data/cbd-large/frame_0023.ply 0.005
#   bench/python.sh -n 1 --pin none fixtures/frame_0040.ply 0.014
#
# Options: -n RUNS (default 3), --pin CPUS: both sides run as `taskset -c CPUS python
# bench/inprocess.py --pin CPUS …` (default 0,1; "none": unpinned; exits 2 without taskset or
# with a CPU not available). The table's header line gives the CPU model, the CPUs available and
# the pinning.
# Environment: SPLASH_PYTHON (a Python with splash_sph; default the test virtualenv in cargo's
# target directory, made by ./scripts/test), PYSPLASHSURF_PYTHON (a Python with pysplashsurf,
# e.g. a throwaway venv with `pip install pysplashsurf==0.14.1`; without one, splash alone).
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=bench/pin.sh
. bench/pin.sh
runs=3 pin=0,1
while [ $# -gt 2 ]; do
    case $1 in
    -n) runs=$2; shift 2 ;;
    --pin) pin=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
    esac
done
[ $# -eq 2 ] || { sed -n 2,17p "$0"; exit 2; }
frame=$(realpath "$1") spacing=$2
pin_setup "$pin"
ours=${SPLASH_PYTHON:-$(scripts/target-dir)/venv/bin/python}
peer=${PYSPLASHSURF_PYTHON:-}
"$ours" -c 'import splash_sph' 2>/dev/null \
    || { echo "no splash_sph in $ours (run ./scripts/test once, or set SPLASH_PYTHON)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$ours" -c "import sys, numpy, splash_sph
numpy.save(sys.argv[2], numpy.asarray(splash_sph.read_particles(sys.argv[1]).positions))" \
    "$frame" "$work/positions.npy"
for _ in $(seq "$runs"); do
    ${pinned[@]+"${pinned[@]}"} "$ours" bench/inprocess.py --pin "$pin" splash "$work/positions.npy" \
        "$spacing" | tee -a "$work/splash"
    if [ -n "$peer" ]; then
        ${pinned[@]+"${pinned[@]}"} "$peer" bench/inprocess.py --pin "$pin" pysplashsurf \
            "$work/positions.npy" "$spacing" | tee -a "$work/peer"
    fi
done
echo
echo "$frame, r = $spacing; splash_sph: $ours; pysplashsurf: ${peer:-none}; $pin_note; $(date -u +%F)"
echo
"$ours" - "$work/splash" "${peer:+$work/peer}" <<'PY'
import statistics, sys
rows = [[line.split() for line in open(p)] for p in sys.argv[1:] if p]
print("| reconstructor | runs | wall s | MiB above positions | triangles |")
print("|---|---|---|---|---|")
for r in rows:
    print(f"| {r[0][0]} | {len(r)} | {statistics.median(float(x[1]) for x in r):.3f} | "
          f"{statistics.median(float(x[2]) for x in r):.1f} | {r[0][3]} |")
if len(rows) == 2:
    t = statistics.median(float(a[1]) / float(b[1]) for a, b in zip(*rows))
    m = statistics.median(float(a[2]) / float(b[2]) for a, b in zip(*rows))
    same = all(a[3] == b[3] for a, b in zip(*rows))
    print(f"\nsplash / pysplashsurf, median of pairs: time {t:.2f}x, memory {m:.2f}x; "
          f"same triangle counts: {same}")
PY
