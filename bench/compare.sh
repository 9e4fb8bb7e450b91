#!/usr/bin/env bash
# Paired wall time and peak memory of splash against splashsurf (if one is on the PATH) on
# particle frames, with the same parameters: density field, compact support 2r, iso 0.6,
# normals on, binary PLY, the same thread count, and `--raw` for splash (splashsurf
# post-processes nothing by default). Runs alternate (splash, splashsurf, splash,
# …) so that a shared machine's drift hits both; the table gives medians over the runs and the
# median of the per-pair ratios. Installs nothing.
#
#   bench/compare.sh -r 0.014 /work/shared/data/cbd-small -r 0.005 /work/shared/data/cbd-large
#   bench/compare.sh -c "2r r r/2" -t 2 -n 3 -r 0.005 spray.ply
#   bench/compare.sh --pin none -r 0.014 fixtures/frame_0040.ply
#
# Options (each applies to the inputs after it): -r SPACING (particle spacing r, required),
# -c CELLS (default "2r r r/2"), -t THREADS (default 2), -n RUNS (pairs per row, default 1).
# --pin CPUS, wherever given, applies to every run: splash and splashsurf alike under `taskset
# -c CPUS` (default 0,1; "none": unpinned; exits 2 without taskset or with a CPU not
# available). The header line gives the CPU model, the CPUs available and the pinning.
# Environment: SPLASH (default release/splash in cargo's target directory), SPLASHSURF
# (default: splashsurf on the PATH; the table leaves its columns empty without one), KEEP (a
# directory to keep the meshes).
set -euo pipefail
# shellcheck source=bench/pin.sh
. "$(dirname "$0")/pin.sh"

splash=${SPLASH:-$("$(dirname "$0")"/../scripts/target-dir)/release/splash}
peer=${SPLASHSURF:-$(command -v splashsurf || true)}
[ -x "$splash" ] || { echo "no splash at $splash (cargo build --release, or set SPLASH)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (GNU time) for peak memory" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out=${KEEP:-$work}
# --pin, wherever it is, for all the runs; the other options in order.
pin_args "$@"
set -- ${args[@]+"${args[@]}"}
pin_setup "$pin"

spacing="" cells="2r r r/2" threads=2 runs=1
median() { sort -g | awk '{a[NR]=$1} END {if (NR) print a[int((NR+1)/2)]}'; }
faces() { sed -n '/end_header/q;s/^element face //p' "$1" | head -1; }
# Times one command: prints "seconds peak_MB".
timed() {
    /usr/bin/time -f "%e %M" -o "$work/time" ${pinned[@]+"${pinned[@]}"} "$@" >"$work/log" 2>&1 || {
        echo "failed: $*" >&2; tail -5 "$work/log" >&2; echo "NA NA"; return; }
    awk '{printf "%s %.0f\n", $1, $2 / 1024}' "$work/time"
}

row() { # frame cell
    local f=$1 cell=$2 name cube a b ss=() ps=() sm=() pm=() ratios=() st pt
    name=$(basename "$(dirname "$f")")/$(basename "$f" .ply)
    # splashsurf's lengths are multiples of its particle radius, r/2.
    cube=$(awk -v c="$cell" 'BEGIN { n = split(c, p, "/"); k = (p[1] == "r" ? 1 : p[1] + 0);
        if (n == 2) k /= p[2]; print 2 * k }')
    for _ in $(seq "$runs"); do
        read -r a b < <(timed "$splash" recon "$f" --spacing "$spacing" --field density \
            --cell "$cell" --normals field --raw --threads "$threads" -o "$out/splash.ply" -q)
        ss+=("$a"); sm+=("$b")
        if [ -n "$peer" ]; then
            read -r a b < <(timed "$peer" reconstruct "$f" -r "$(awk -v r="$spacing" 'BEGIN{print r/2}')" \
                -l 2.0 -c "$cube" -t 0.6 --normals=on -n "$threads" -o "$out/splashsurf.ply")
            ps+=("$a"); pm+=("$b")
            ratios+=("$(awk -v x="${ss[-1]}" -v y="$a" 'BEGIN{ if (y > 0 && x != "NA") printf "%.2f", x / y; else print "NA" }')")
        fi
    done
    st=$(faces "$out/splash.ply" 2>/dev/null || true)
    if [ -n "$peer" ]; then
        pt=$(faces "$out/splashsurf.ply" 2>/dev/null || true)
        printf '| %s | %s | %s | %s | %s | %s MB | %s MB | %s | %s |\n' "$name" "$cell" \
            "$(printf '%s\n' "${ss[@]}" | median)" "$(printf '%s\n' "${ps[@]}" | median)" \
            "$(printf '%s\n' "${ratios[@]}" | median)" "$(printf '%s\n' "${sm[@]}" | median)" \
            "$(printf '%s\n' "${pm[@]}" | median)" "$st" "$pt"
    else
        printf '| %s | %s | %s | | | %s MB | | %s | |\n' "$name" "$cell" \
            "$(printf '%s\n' "${ss[@]}" | median)" "$(printf '%s\n' "${sm[@]}" | median)" "$st"
    fi
}

echo "splash: $splash; splashsurf: ${peer:-none on the PATH}; $pin_note; $(date -u +%F)"
echo
echo "| frame | cell | splash s | splashsurf s | ratio | splash peak | splashsurf peak | splash triangles | splashsurf triangles |"
echo "|---|---|---|---|---|---|---|---|---|"
while [ $# -gt 0 ]; do
    case $1 in
    -r) spacing=$2; shift 2 ;;
    -c) cells=$2; shift 2 ;;
    -t) threads=$2; shift 2 ;;
    -n) runs=$2; shift 2 ;;
    *)
        [ -n "$spacing" ] || { echo "give the spacing with -r before $1" >&2; exit 2; }
        if [ -d "$1" ]; then files=("$1"/*.ply); else files=("$1"); fi
        for f in "${files[@]}"; do
            for cell in $cells; do row "$f" "$cell"; done
        done
        shift ;;
    esac
done
