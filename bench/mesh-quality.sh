#!/usr/bin/env bash
# Issue 25's render-quality table over a folder of PLY meshes, each against the particle frame
# of the same file name: volume error V/(N r^3) - 1, bumpiness (area-weighted mean dihedral
# angle), slivers (< 10 deg), faces, closed/manifold, components of <= 20 faces, self-intersecting
# faces (exact test).
#
#   bench/mesh-quality.sh SPACING PARTICLES_DIR MESH_DIR [SLIVER_FRAME]
#   e.g. splash recon ../shared/data/cbd-small --cell r/2 --format ply -o /tmp/m/ &&
#        bench/mesh-quality.sh 0.014 ../shared/data/cbd-small /tmp/m frame_0040.ply
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 3 ] || { sed -n 2,9p "$0"; exit 2; }
spacing=$1; particles=$(realpath "$2"); meshes=$(realpath "$3"); shift 3
exec cargo run -q --release -p splash-sph --example mesh_quality -- --spacing "$spacing" "$particles" "$meshes" "$@"
