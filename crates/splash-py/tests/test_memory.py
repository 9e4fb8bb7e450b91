"""Repeated calls do not leak."""

import splash_sph
from conftest import ball


def resident_bytes():
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * 4096


def test_repeated_reconstructions_do_not_grow(tmp_path):
    x = ball(0.1, radius=0.8)
    velocity = x * 2.0
    for i in range(200):
        mesh = splash_sph.reconstruct(x, spacing=0.1, threads=2, attributes={"velocity": velocity})
        assert len(mesh.faces) > 100
        if i == 19:
            after_20 = resident_bytes()
        del mesh
    growth = resident_bytes() - after_20
    # A mesh here holds about 0.25 MB (vertices, normals, faces, velocities): leaking one per
    # call would add 45 MB. Allocator caches make the resident size wander by a few MB.
    assert growth < 4 * 2**20, f"resident memory grew by {growth / 2**20:.1f} MiB"
