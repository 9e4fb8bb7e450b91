#!/usr/bin/env bash
# Issue 25's closing table: splash --raw, splash's default, splash --decimate 0.1r and
# splashsurf's recommended post-processing (density field, weighted smoothing 25 iterations,
# cleanup, normal smoothing 10; if splashsurf is on the PATH) on a folder of frames or one
# frame, SSP07 (splash's default field) at cell r/2, 2 threads: the quality columns of
# bench/mesh-quality.sh (volume error, bumpiness, slivers of one frame, mean faces) and the
# wall time and peak memory of the whole run, medians over runs that alternate the pipelines,
# with the per-run ratio to the --raw run. Installs nothing.
#
#   bench/render-ready.sh -r 0.014 -s frame_0040.ply ../shared/data/cbd-small \
#       -r 0.005 ../shared/data/cbd-large/frame_0023.ply
#   bench/render-ready.sh --pin none -n 1 -r 0.014 fixtures/frame_0040.ply
#
# Options (each applies to the inputs after it): -r SPACING (required), -t THREADS (default 2),
# -n RUNS (default 3), -s FRAME (the file name whose slivers are shown; default the last).
# --pin CPUS, wherever given, applies to every timed run: the splash pipelines and splashsurf
# alike under `taskset -c CPUS` (default 0,1; "none": unpinned; exits 2 without taskset or with
# a CPU not available); the quality scoring is not timed and not pinned. The header lines give
# the CPU model, the CPUs available and the pinning.
# Environment: SPLASH (default release/splash in cargo's target directory), SPLASHSURF (default:
# splashsurf on the PATH), KEEP (a directory to keep the meshes).
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=bench/pin.sh
. bench/pin.sh
# --pin, wherever it is, for all the runs; the other options in order.
pin_args "$@"
set -- ${args[@]+"${args[@]}"}
pin_setup "$pin"

splash=${SPLASH:-$(scripts/target-dir)/release/splash}
peer=${SPLASHSURF:-$(command -v splashsurf || true)}
[ -x "$splash" ] || { echo "no splash at $splash (cargo build --release, or set SPLASH)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (GNU time) for peak memory" >&2; exit 2; }
cargo build -q --release -p splash-sph --example mesh_quality
quality=$(scripts/target-dir)/release/examples/mesh_quality
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out=${KEEP:-$work}

spacing="" threads=2 runs=3 sliver=""
# (Empty lines, as from the space-separated lists below, are no values.)
median() { sort -g | awk 'NF {a[++n] = $1} END {if (n) print a[int((n + 1) / 2)]}'; }
ratio() { awk -v x="$1" -v y="$2" 'BEGIN{ if (y > 0 && x != "NA") printf "%.2f", x / y; else print "NA" }'; }
# Runs one command: prints "seconds peak_MiB".
timed() {
    /usr/bin/time -f "%e %M" -o "$work/time" ${pinned[@]+"${pinned[@]}"} "$@" >"$work/log" 2>&1 || {
        echo "failed: $*" >&2; tail -5 "$work/log" >&2; echo "NA NA"; return; }
    awk '{printf "%s %.1f\n", $1, $2 / 1024}' "$work/time"
}
# One pipeline on input $2 into the empty folder $out/$1.
run() { # name input
    local dir=$out/$1 input=$2 frames
    rm -rf "$dir"; mkdir -p "$dir"
    case $1 in
    raw) timed "$splash" recon "$input" --spacing "$spacing" --cell r/2 --raw --threads "$threads" --format ply -o "$dir/" -q ;;
    default) timed "$splash" recon "$input" --spacing "$spacing" --cell r/2 --threads "$threads" --format ply -o "$dir/" -q ;;
    decimate) timed "$splash" recon "$input" --spacing "$spacing" --cell r/2 --decimate 0.1r --threads "$threads" --format ply -o "$dir/" -q ;;
    peer)
        if [ -d "$input" ]; then frames=("$input/frame_{}.ply" --mt-files=on -o "frame_{}.ply")
        else frames=("$input" -o "$(basename "$input")"); fi
        timed "$peer" reconstruct "${frames[0]}" -r "$(awk -v r="$spacing" 'BEGIN{print r/2}')" -l 2.0 \
            -c 1.0 -t 0.6 --normals=on --mesh-smoothing-weights=on --mesh-smoothing-iters=25 \
            --mesh-cleanup=on --normals-smoothing-iters=10 -n "$threads" --output-dir "$dir" \
            "${frames[@]:1}" -q ;;
    esac
}

table() { # input
    local input=$1 particles names=(raw default decimate) name a b last
    [ -n "$peer" ] && names+=(peer)
    if [ -d "$input" ]; then particles=$input; last=$(ls "$input"/frame_*.ply | tail -1)
    else particles=$(dirname "$input"); last=$input; fi
    [ -n "$sliver" ] && last=$particles/$sliver
    declare -A secs mibs rats
    for _ in $(seq "$runs"); do
        for name in "${names[@]}"; do
            read -r a b < <(run "$name" "$input")
            secs[$name]+="$a "; mibs[$name]+="$b "
        done
        for name in "${names[@]}"; do
            rats[$name]+="$(ratio "$(echo "${secs[$name]}" | awk '{print $NF}')" \
                "$(echo "${secs[raw]}" | awk '{print $NF}')") "
        done
    done
    echo "$input, r = $spacing, cell r/2, $threads threads, $runs runs; $pin_note; slivers of $(basename "$last")"
    echo
    echo "| pipeline | volume error min … max (mean abs) | bumpiness | slivers | faces (mean) | wall s | ÷ raw | peak MiB |"
    echo "|---|---|---|---|---|---|---|---|"
    for name in "${names[@]}"; do
        "$quality" --spacing "$spacing" "$particles" "$out/$name" "$(basename "$last")" >"$work/q" ||
            { echo "quality failed for $name" >&2; cat "$work/q" >&2; }
        sed -n 's/^summary ([0-9]* meshes): volume error \(.*\) | bumpiness \(.*\) | slivers \([^(]*\) (.*) | faces \(.*\)$/\1\t\2\t\3\t\4/p' "$work/q" |
            awk -F'\t' -v n="$name" -v s="$(echo "${secs[$name]}" | tr ' ' '\n' | median)" \
                -v r="$(echo "${rats[$name]}" | tr ' ' '\n' | median)" \
                -v m="$(echo "${mibs[$name]}" | tr ' ' '\n' | median)" \
                '{printf "| %s | %s | %s | %s | %s | %s | %s | %s |\n", n, $1, $2, $3, $4, s, r, m}'
    done
    echo
}

echo "splash: $splash; splashsurf: ${peer:-none on the PATH}; $pin_note; $(date -u +%F)"
while [ $# -gt 0 ]; do
    case $1 in
    -r) spacing=$2; shift 2 ;;
    -t) threads=$2; shift 2 ;;
    -n) runs=$2; shift 2 ;;
    -s) sliver=$2; shift 2 ;;
    *)
        [ -n "$spacing" ] || { echo "give the spacing with -r before $1" >&2; exit 2; }
        table "$1"
        shift ;;
    esac
done
