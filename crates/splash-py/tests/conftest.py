"""Shared fixtures: the repository's particle frames, the splash CLI, small particle sets."""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import splash_sph

REPO = Path(__file__).resolve().parents[3]
FRAME = REPO / "fixtures" / "frame_0040.ply"
# The simulation's particle spacing of the fixture frames.
FRAME_SPACING = 0.014


@pytest.fixture(scope="session")
def frame():
    """fixtures/frame_0040.ply, read once."""
    return splash_sph.read_particles(FRAME)


@pytest.fixture(scope="session")
def splash_bin():
    """The CLI: $SPLASH_BIN, else release/splash in cargo's target directory (target/ unless
    CARGO_TARGET_DIR or a cargo config says otherwise), built here when missing."""
    path = os.environ.get("SPLASH_BIN")
    if not path:
        target = subprocess.run(
            [REPO / "scripts" / "target-dir"], capture_output=True, text=True, check=True
        ).stdout.strip()
        path = Path(target) / "release" / "splash"
    path = Path(path)
    if not path.is_absolute():
        path = REPO / path
    if not path.exists():
        subprocess.run(["cargo", "build", "--release", "-p", "splash"], cwd=REPO, check=True)
    assert path.exists(), f"no splash binary at {path}"
    return path


def ball(spacing=0.1, radius=0.5):
    """Particles on a cubic lattice of `spacing` within `radius` of the origin, float32."""
    k = int(radius / spacing) + 1
    axis = np.arange(-k, k + 1) * spacing
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    return np.ascontiguousarray(grid[np.linalg.norm(grid, axis=1) <= radius], dtype=np.float32)


def read_obj(path):
    """Vertices (V, 3) float32 and faces (F, 3) uint32 (0-based) of an OBJ file from splash."""
    vertices, faces = [], []
    for line in Path(path).read_text().splitlines():
        if line.startswith("v "):
            vertices.append([float(x) for x in line.split()[1:]])
        elif line.startswith("f "):
            faces.append([int(c.split("/")[0]) - 1 for c in line.split()[1:]])
    return (
        np.array(vertices, dtype=np.float32).reshape(-1, 3),
        np.array(faces, dtype=np.uint32).reshape(-1, 3),
    )


def read_ply_columns(path):
    """The vertex properties of a binary little-endian PLY file whose properties are all
    float, by name."""
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    assert "format binary_little_endian 1.0" in header
    names = [line.split()[2] for line in header if line.startswith("property float ")]
    count = next(int(line.split()[2]) for line in header if line.startswith("element vertex "))
    records = np.frombuffer(data, dtype=[(n, "<f4") for n in names], count=count, offset=end)
    return {n: records[n] for n in names}
