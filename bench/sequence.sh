#!/usr/bin/env bash
# Paired wall time and peak memory of a whole sequence: `splash recon DIR -o OUT/` against
# splashsurf (if one is on the PATH) with `--mt-files=on` (its frames in parallel), the same
# parameters (density field, compact support 2r, iso 0.6, normals on, cell r/2 by default:
# splashsurf's -c 1.0 of its radius r/2), `--raw` for splash (splashsurf post-processes
# nothing by default), the same thread count, in each mesh format asked. Runs alternate
# (splash, splashsurf, splash, …) so that a shared machine's drift hits both; the table gives
# medians over the runs and the median of the per-pair ratios. Installs nothing.
#
#   bench/sequence.sh -r 0.014 /work/shared/data/cbd-small
#   bench/sequence.sh -f "obj ply" -t 2 -n 5 -r 0.014 /work/shared/data/cbd-small
#   bench/sequence.sh --pin none -r 0.014 /work/shared/data/cbd-small
#
# Options (each applies to the directories after it): -r SPACING (particle spacing r,
# required), -c CELL (r/2, r or 2r; default r/2), -f FORMATS (default "obj ply"), -t THREADS
# (default 2), -n RUNS (pairs per row, default 3). --pin CPUS, wherever given, applies to every
# run: splash, splashsurf and BASE alike under `taskset -c CPUS` (default 0,1; "none":
# unpinned; exits 2 without taskset or with a CPU not available). The header line gives the
# CPU model, the CPUs available and the pinning. Directories hold `frame_NNNN.ply` files.
# Environment: SPLASH (default release/splash in cargo's target directory), SPLASHSURF
# (default: splashsurf on the PATH; the table leaves its columns empty without one), BASE (a
# second splash binary, timed too, with the ratio splash / BASE: a before-and-after).
set -euo pipefail
# shellcheck source=bench/pin.sh
. "$(dirname "$0")/pin.sh"

splash=${SPLASH:-$("$(dirname "$0")"/../scripts/target-dir)/release/splash}
peer=${SPLASHSURF:-$(command -v splashsurf || true)}
base=${BASE:-}
[ -x "$splash" ] || { echo "no splash at $splash (cargo build --release, or set SPLASH)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (GNU time) for peak memory" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# --pin, wherever it is, for all the runs; the other options in order.
pin_args "$@"
set -- ${args[@]+"${args[@]}"}
pin_setup "$pin"

spacing="" cell="r/2" formats="obj ply" threads=2 runs=3
median() { sort -g | awk '{a[NR]=$1} END {if (NR) print a[int((NR+1)/2)]}'; }
ratio() { awk -v x="$1" -v y="$2" 'BEGIN{ if (y > 0 && x != "NA") printf "%.2f", x / y; else print "NA" }'; }
# Times one command: prints "seconds peak_MB".
timed() {
    /usr/bin/time -f "%e %M" -o "$work/time" ${pinned[@]+"${pinned[@]}"} "$@" >"$work/log" 2>&1 || {
        echo "failed: $*" >&2; tail -5 "$work/log" >&2; echo "NA NA"; return; }
    awk '{printf "%s %.0f\n", $1, $2 / 1024}' "$work/time"
}
splash_run() { # binary dir format
    rm -rf "$work/out"
    timed "$1" recon "$2" --spacing "$spacing" --cell "$cell" --field density --raw \
        --threads "$threads" --format "$3" -o "$work/out/" -q
}
peer_run() { # dir format
    rm -rf "$work/peer"; mkdir -p "$work/peer"
    local k
    k=$(awk -v c="$cell" 'BEGIN { n = split(c, p, "/"); k = (p[1] == "r" ? 1 : p[1] + 0);
        if (n == 2) k /= p[2]; print 2 * k }')
    timed "$peer" reconstruct "$1/frame_{}.ply" -r "$(awk -v r="$spacing" 'BEGIN{print r/2}')" \
        -l 2.0 -c "$k" -t 0.6 --normals=on --mt-files=on -n "$threads" \
        --output-dir "$work/peer" -o "frame_{}.$2" -q
}

row() { # dir format
    local dir=$1 format=$2 a b ss=() sm=() ps=() pm=() bs=() r_peer=() r_base=()
    for _ in $(seq "$runs"); do
        read -r a b < <(splash_run "$splash" "$dir" "$format"); ss+=("$a"); sm+=("$b")
        if [ -n "$peer" ]; then
            read -r a b < <(peer_run "$dir" "$format"); ps+=("$a"); pm+=("$b")
            r_peer+=("$(ratio "${ss[-1]}" "$a")")
        fi
        if [ -n "$base" ]; then
            read -r a b < <(splash_run "$base" "$dir" "$format"); bs+=("$a")
            r_base+=("$(ratio "${ss[-1]}" "$a")")
        fi
    done
    printf '| %s | %s | %s | %s | %s MB | %s | %s | %s MB | %s | %s |\n' \
        "$(basename "$dir")" "$format" "$(ls "$dir"/frame_*.ply | wc -l)" \
        "$(printf '%s\n' "${ss[@]}" | median)" "$(printf '%s\n' "${sm[@]}" | median)" \
        "$(printf '%s\n' "${ps[@]}" | median)" "$(printf '%s\n' "${r_peer[@]}" | median)" \
        "$(printf '%s\n' "${pm[@]}" | median)" \
        "$(printf '%s\n' "${bs[@]}" | median)" "$(printf '%s\n' "${r_base[@]}" | median)"
}

echo "splash: $splash; splashsurf: ${peer:-none on the PATH}; base: ${base:-none}; $pin_note; $(date -u +%F)"
echo
echo "| sequence | format | frames | splash s | splash peak | splashsurf s | ratio | splashsurf peak | base s | ratio to base |"
echo "|---|---|---|---|---|---|---|---|---|---|"
while [ $# -gt 0 ]; do
    case $1 in
    -r) spacing=$2; shift 2 ;;
    -c) cell=$2; shift 2 ;;
    -f) formats=$2; shift 2 ;;
    -t) threads=$2; shift 2 ;;
    -n) runs=$2; shift 2 ;;
    *)
        [ -n "$spacing" ] || { echo "give the spacing with -r before $1" >&2; exit 2; }
        for format in $formats; do row "$1" "$format"; done
        shift ;;
    esac
done
