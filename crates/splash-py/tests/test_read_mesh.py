"""splash_sph.read_mesh (the library's mesh readers; what the Blender add-on loads farm
sequences with): every format the writers produce reads back as the Mesh that wrote it, bit
for bit, and meshio agrees on VTU; broken files raise ValueError naming the file."""

import random
import subprocess

import numpy as np
import pytest

import splash_sph
from conftest import FRAME, FRAME_SPACING


@pytest.fixture(scope="module")
def mesh(frame):
    """The fixture frame's surface with velocity and density."""
    return splash_sph.reconstruct(
        frame.positions,
        FRAME_SPACING,
        cell="r",
        attributes={"velocity": frame["velocity"], "density": frame["density"]},
    )


def same(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("fmt", ["obj", "ply", "ply-ascii", "vtk", "vtu", "vtp"])
def test_read_mesh_gives_back_the_written_mesh(mesh, tmp_path, fmt):
    ext = "ply" if fmt.startswith("ply") else fmt
    path = tmp_path / f"f.{ext}"
    mesh.write(path, format=fmt)  # OBJ leaves the attributes out
    back = splash_sph.read_mesh(path)
    assert isinstance(back, splash_sph.MeshArrays)
    assert same(back.vertices, mesh.vertices)
    assert same(back.faces, mesh.faces)
    assert same(back.normals, mesh.normals)
    if fmt == "obj":
        assert back.attributes == {}
    else:
        assert sorted(back.attributes) == ["density", "velocity"]
        for name, values in mesh.attributes.items():
            assert same(back.attributes[name], values), name


def test_read_mesh_vtu_agrees_with_meshio(mesh, tmp_path):
    meshio = pytest.importorskip("meshio")
    mesh.write(tmp_path / "f.vtu")
    ours, theirs = splash_sph.read_mesh(tmp_path / "f.vtu"), meshio.read(tmp_path / "f.vtu")
    assert np.array_equal(ours.vertices, theirs.points)
    assert np.array_equal(ours.faces, theirs.cells_dict["triangle"])
    assert np.array_equal(ours.attributes["velocity"], theirs.point_data["velocity"])


def test_read_mesh_of_the_cli_output(splash_bin, tmp_path):
    for fmt in ["obj", "ply"]:
        out = tmp_path / f"f.{fmt}"
        extra = [] if fmt == "obj" else ["--attributes", "velocity"]
        subprocess.run(
            [str(splash_bin), "recon", str(FRAME), "--spacing", str(FRAME_SPACING), "--cell",
             "r", "-q", "-o", str(out), *extra],
            check=True,
        )  # fmt: skip
    obj, ply = splash_sph.read_mesh(tmp_path / "f.obj"), splash_sph.read_mesh(tmp_path / "f.ply")
    assert len(ply.faces) > 10_000
    assert same(obj.vertices, ply.vertices) and same(obj.faces, ply.faces)
    assert same(obj.normals, ply.normals)
    assert ply.attributes["velocity"].shape == (len(ply.vertices), 3)


@pytest.mark.parametrize(
    "name, content, message",
    [
        ("a.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 10\n", "end_header"),
        (
            "b.ply",
            b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\n"
            b"property float y\nproperty float z\nelement face 0\n"
            b"property list uchar int vertex_indices\nend_header\n" + bytes(12),
            "too short",
        ),
        (
            "g.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float x\n"
            b"property float z\nelement face 0\nproperty int vertex_indices\nend_header\n",
            "same name",
        ),
        (
            "h.ply",
            b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
            b"property float z\nelement face 1\nproperty int vertex_indices\nend_header\n3\n",
            "list property 'vertex_indices'",
        ),
        ("c.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 4\n", "4 corners"),
        ("d.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "refers to vertex 8"),
        ("e.vtu", b"<VTKFile><Unstructured", "VTK XML"),
        ("f.stl", b"solid", "extension"),
    ],
)
def test_read_mesh_refuses_broken_files(tmp_path, name, content, message):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(ValueError, match=message) as info:
        splash_sph.read_mesh(path)
    assert name in str(info.value)


def test_read_mesh_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError):
        splash_sph.read_mesh(tmp_path / "none.ply")


@pytest.mark.parametrize("fmt", ["obj", "ply", "ply-ascii", "vtk", "vtu"])
def test_read_mesh_mutated_files_raise_value_errors_only(mesh, tmp_path, fmt):
    """Bytes changed, cut, inserted or truncated (seeded): read_mesh returns a mesh or raises
    ValueError naming the file, nothing else."""
    ext = "ply" if fmt.startswith("ply") else fmt
    small = splash_sph.reconstruct(mesh.vertices[::50], 0.05, cell="2r")
    small.write(tmp_path / f"seed.{ext}", format=fmt)
    data = (tmp_path / f"seed.{ext}").read_bytes()
    rng = random.Random(0x5EED)
    path = tmp_path / f"case.{ext}"
    for _ in range(200):
        d = bytearray(data)
        for _ in range(rng.randint(1, 6)):
            if not d:
                break
            i, op = rng.randrange(len(d)), rng.random()
            if op < 0.5:
                d[i] = rng.randrange(256)
            elif op < 0.7:
                del d[i : i + rng.randint(1, 50)]
            elif op < 0.85:
                d[i:i] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 8)))
            else:
                del d[i:]
        path.write_bytes(bytes(d))
        try:
            splash_sph.read_mesh(path)
        except ValueError as e:
            assert "case." in str(e)
