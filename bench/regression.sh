#!/usr/bin/env bash
# Issue 39's first table: an older splash binary against a newer one on the raw path, both on
# the same CPUs (`taskset -c CPUS`, as a farm node gives a job no idle core), runs alternating
# (old, new, old, …) so that a shared machine's drift hits both; medians of the wall times and
# of the per-pair ratios new / old, and whether the two wrote the same bytes (`cmp`). The old
# binary may predate `--raw` (post-processing became the default later): it is given the same
# command without it, which wrote the raw isosurface then.
#
#   bench/regression.sh /path/to/splash-104c9ab target/release/splash
#   bench/regression.sh -n 5 --pin 0,1 -d ../shared/data OLD NEW
#
# Options: -n RUNS (pairs per row, default 5), --pin CPUS (both binaries under `taskset -c
# CPUS`; default 0,1; "none": unpinned; exits 2 without taskset or with a CPU not available),
# -t THREADS (default 2), -d DATA (the shared frames, default ../shared/data). The header line
# gives the CPU model, the CPUs available and the pinning. Installs nothing.
set -euo pipefail
# shellcheck source=bench/pin.sh
. "$(dirname "$0")/pin.sh"

runs=5 pin=0,1 threads=2 data=../shared/data
while [ $# -gt 2 ]; do
    case $1 in
    -n) runs=$2; shift 2 ;;
    --pin) pin=$2; shift 2 ;;
    -t) threads=$2; shift 2 ;;
    -d) data=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
    esac
done
[ $# -eq 2 ] || { echo "usage: bench/regression.sh [-n RUNS] [--pin CPUS] [-t THREADS] [-d DATA] OLD NEW" >&2; exit 2; }
old=$1 new=$2
pin_setup "$pin"
for b in "$old" "$new"; do [ -x "$b" ] || { echo "not an executable: $b" >&2; exit 2; }; done
[ -d "$data/cbd-small" ] || { echo "skipped: no frames in $data (cbd-small, cbd-large)" >&2; exit 0; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The old binary takes --raw only if it knows it.
old_raw=()
"$old" recon --help 2>/dev/null | grep -q -- '--raw' && old_raw=(--raw)

median() { sort -g | awk '{a[NR]=$1} END {if (NR) print a[int((NR+1)/2)]}'; }
# Wall seconds of one run, its outputs in $2.
wall() { # out binary args...
    local out=$1; shift
    rm -rf "$out"
    local start end
    start=$(date +%s.%N)
    ${pinned[@]+"${pinned[@]}"} "$@" -q -o "$out/" >"$work/log" 2>&1 || { tail -3 "$work/log" >&2; echo NA; return; }
    end=$(date +%s.%N)
    awk -v a="$start" -v b="$end" 'BEGIN { printf "%.4f\n", b - a }'
}

row() { # label input spacing extra-args...
    local label=$1 input=$2 spacing=$3; shift 3
    local args=(recon "$input" --spacing "$spacing" --cell r/2 --threads "$threads" "$@")
    local a b olds=() news=() ratios=() same=yes
    for _ in $(seq "$runs"); do
        a=$(wall "$work/old" "$old" "${args[@]}" "${old_raw[@]}")
        b=$(wall "$work/new" "$new" "${args[@]}" --raw)
        olds+=("$a"); news+=("$b")
        ratios+=("$(awk -v x="$b" -v y="$a" 'BEGIN { if (y > 0 && x != "NA") printf "%.3f", x / y; else print "NA" }')")
    done
    for f in "$work"/old/*; do
        cmp -s "$f" "$work/new/$(basename "$f")" || same=no
    done
    printf '| %s | %s | %s | %s | %s |\n' "$label" \
        "$(printf '%s\n' "${olds[@]}" | median)" "$(printf '%s\n' "${news[@]}" | median)" \
        "$(printf '%s\n' "${ratios[@]}" | median)" "$same"
}

echo "old: $old; new: $new; $pin_note; $threads threads; $runs alternating pairs; $(date -u +%F)"
echo "| work | old s | new s | new ÷ old | same bytes |"
echo "|---|---|---|---|---|"
row "cbd-small f40, density r/2" "$data/cbd-small/frame_0040.ply" 0.014 --field density
row "cbd-large f23, density r/2" "$data/cbd-large/frame_0023.ply" 0.005 --field density
row "cbd-large f23, SSP07 r/2" "$data/cbd-large/frame_0023.ply" 0.005
row "21 cbd-small frames -> PLY, density r/2" "$data/cbd-small" 0.014 --field density --format ply
