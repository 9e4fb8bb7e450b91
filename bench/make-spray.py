#!/usr/bin/env python3
"""Writes the sparse "spray" benchmark frame of issue 15: a particle frame (binary PLY, x y z)
plus N particles scattered uniformly in a cube beside the fluid's bounding box, each far from
every other (an isolated droplet), to measure what a droplet costs. Standard library only;
the same seed gives the same file.

    python3 bench/make-spray.py /work/shared/data/cbd-large/frame_0023.ply /tmp/spray.ply
    python3 bench/make-spray.py IN OUT --count 105000 --side 10 --seed 15
"""
import argparse
import random
import struct
import sys


def read_ply_xyz(path):
    """The x y z payload (little-endian f32 triples) of a binary little-endian PLY whose vertex
    properties are all floats; other properties are dropped."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    if header[1] != "format binary_little_endian 1.0":
        sys.exit(f"{path}: expected a binary little-endian PLY, got {header[1]!r}")
    props = [l.split() for l in header if l.startswith("property")]
    count = [int(l.split()[-1]) for l in header if l.startswith("element vertex")][0]
    names = [p[-1] for p in props]
    if any(p[1] != "float" for p in props) or names[:3] != ["x", "y", "z"]:
        sys.exit(f"{path}: expected float properties starting with x y z, got {props}")
    stride = len(names)
    if len(data) - end < 4 * stride * count:
        sys.exit(f"{path}: {count} vertices announced, fewer stored")
    if stride == 3:
        return count, data[end : end + 12 * count]
    values = struct.unpack_from(f"<{stride * count}f", data, end)
    xyz = [v for i in range(count) for v in values[i * stride : i * stride + 3]]
    return count, struct.pack(f"<{3 * count}f", *xyz)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--count", type=int, default=105_000, help="droplets to add")
    ap.add_argument("--side", type=float, default=10.0, help="side of the droplets' cube (m)")
    ap.add_argument("--gap", type=float, default=0.5, help="gap between fluid and cube (m)")
    ap.add_argument("--seed", type=int, default=15)
    a = ap.parse_args()
    count, body = read_ply_xyz(a.input)
    xs = struct.unpack_from(f"<{3 * count}f", body)
    lo = [min(xs[i::3]) for i in range(3)]
    hi = [max(xs[i::3]) for i in range(3)]
    rng = random.Random(a.seed)
    # The cube starts `gap` beyond the fluid's largest x and spans `side` on every axis.
    x0, y0, z0 = hi[0] + a.gap, lo[1], lo[2]
    extra = bytearray()
    for _ in range(a.count):
        p = (x0 + rng.random() * a.side, y0 + rng.random() * a.side, z0 + rng.random() * a.side)
        extra += struct.pack("<3f", *p)
    n = count + a.count
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"comment {a.input} plus {a.count} droplets in a {a.side} m cube, seed {a.seed}\n"
        f"element vertex {n}\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
    )
    with open(a.output, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(body)
        f.write(extra)
    print(f"{a.output}: {count} + {a.count} = {n} particles")


if __name__ == "__main__":
    main()
