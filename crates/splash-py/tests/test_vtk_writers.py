"""The VTK writers (.vtk, .vtu, .vtp) read back by independent readers (VTK's own Python
package, and meshio where it reads the format), against the PLY written for the same frame;
--attributes refused where the format has no room; --particle-aabb."""

import json
import subprocess

import numpy as np
import pytest

from conftest import FRAME, FRAME_SPACING

meshio = pytest.importorskip("meshio")


def recon(splash_bin, inp, out, *extra, check=True):
    return subprocess.run(
        [str(splash_bin), "recon", str(inp), "--spacing", str(FRAME_SPACING), "-o", str(out),
         *extra],
        capture_output=True, text=True, check=check,
    )


@pytest.fixture(scope="module")
def written(splash_bin, tmp_path_factory):
    """The fixture frame's mesh with velocity and density, as PLY, VTK, VTU and VTP."""
    d = tmp_path_factory.mktemp("vtk")
    for ext in ["ply", "vtk", "vtu", "vtp"]:
        recon(splash_bin, FRAME, d / f"f.{ext}", "--attributes", "velocity,density")
    ply = meshio.read(d / "f.ply")
    pd = ply.point_data
    expected = {
        "points": ply.points,
        "triangles": ply.cells_dict["triangle"],
        "Normals": np.c_[pd["nx"], pd["ny"], pd["nz"]],
        "velocity": np.c_[pd["vx"], pd["vy"], pd["vz"]],
        "density": pd["density"],
    }
    assert expected["points"].dtype == np.float32 and len(expected["triangles"]) > 100_000
    return d, expected


def same(a, b):
    """Bit-exact equality of float32 arrays (and equal shapes)."""
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.tobytes() == b.astype(a.dtype).tobytes()


def test_vtu_read_by_meshio_matches_the_ply(written):
    d, expected = written
    m = meshio.read(d / "f.vtu")
    assert m.points.dtype == np.float32
    assert same(m.points, expected["points"])
    assert np.array_equal(m.cells_dict["triangle"], expected["triangles"])
    for name in ["Normals", "velocity", "density"]:
        assert same(m.point_data[name].reshape(expected[name].shape), expected[name]), name


@pytest.mark.parametrize("ext", ["vtk", "vtu", "vtp"])
def test_vtk_reads_every_writer_like_the_ply(written, ext):
    vtk = pytest.importorskip("vtk")
    from vtk.util.numpy_support import vtk_to_numpy

    d, expected = written
    reader = {
        "vtk": vtk.vtkPolyDataReader,
        "vtu": vtk.vtkXMLUnstructuredGridReader,
        "vtp": vtk.vtkXMLPolyDataReader,
    }[ext]()
    reader.SetFileName(str(d / f"f.{ext}"))
    reader.Update()
    out = reader.GetOutput()
    assert same(vtk_to_numpy(out.GetPoints().GetData()), expected["points"])
    cells = out.GetCells() if ext == "vtu" else out.GetPolys()
    offsets = vtk_to_numpy(cells.GetOffsetsArray())
    assert np.array_equal(np.diff(offsets), np.full(len(expected["triangles"]), 3))
    triangles = vtk_to_numpy(cells.GetConnectivityArray()).reshape(-1, 3)
    assert np.array_equal(triangles, expected["triangles"])
    if ext == "vtu":
        assert out.IsHomogeneous() and out.GetCellType(0) == vtk.VTK_TRIANGLE
    data = out.GetPointData()
    assert data.GetNormals().GetName() == "Normals"
    for name in ["Normals", "velocity", "density"]:
        values = vtk_to_numpy(data.GetArray(name))
        assert same(values, expected[name]), name
    assert data.GetArray("velocity").GetNumberOfComponents() == 3


def test_attribute_formats_and_names_are_checked(splash_bin, tmp_path):
    for fmt in ["obj", "pov"]:
        r = recon(splash_bin, FRAME, tmp_path / "out/", "--format", fmt, "--attributes", "velocity",
                  check=False)
        assert r.returncode != 0
        assert "no place for vertex attributes" in r.stderr
        assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
    r = recon(splash_bin, FRAME, tmp_path / "m.vtu", "--attributes", "temperature", check=False)
    assert r.returncode != 0
    assert "no particle attribute 'temperature'; it has density, velocity" in r.stderr, r.stderr
    assert not (tmp_path / "m.vtu").exists()
    # Spellings of the alias table find the velocity and are written under its one name.
    recon(splash_bin, FRAME, tmp_path / "v.vtu", "--attributes", "vel,rho")
    assert set(meshio.read(tmp_path / "v.vtu").point_data) == {"Normals", "velocity", "density"}


def write_ply(path, columns):
    """A binary little-endian PLY of float32 columns, written here (not by splash)."""
    names = list(columns)
    n = len(columns[names[0]])
    header = "ply\nformat binary_little_endian 1.0\nelement vertex %d\n" % n
    header += "".join(f"property float {name}\n" for name in names) + "end_header\n"
    records = np.empty(n, dtype=[(name, "<f4") for name in names])
    for name in names:
        records[name] = columns[name]
    path.write_bytes(header.encode() + records.tobytes())


def test_particle_box_drops_escaped_particles(splash_bin, tmp_path):
    m = meshio.read(FRAME)
    columns = {"x": m.points[:, 0], "y": m.points[:, 1], "z": m.points[:, 2]}
    columns.update({k: v for k, v in m.point_data.items()})
    lo, hi = m.points.min(axis=0), m.points.max(axis=0)
    escaped = {k: np.append(v, 1e30 if k in "xyz" else 0.0) for k, v in columns.items()}
    write_ply(tmp_path / "escaped_0040.ply", escaped)
    box = ",".join(repr(float(x)) for x in [*lo, *hi])
    # Without a box the escaped particle fails the frame, as before.
    r = recon(splash_bin, tmp_path / "escaped_0040.ply", tmp_path / "no_box.ply", check=False)
    assert r.returncode != 0 and not (tmp_path / "no_box.ply").exists()
    r = recon(splash_bin, tmp_path / "escaped_0040.ply", tmp_path / "box.ply",
              "--particle-aabb", box, "--attributes", "velocity", "--log-format", "json")
    frame = next(json.loads(line) for line in r.stderr.splitlines() if '"frame"' in line)
    assert frame["particles_outside_box"] == 1
    assert frame["particles"] == len(m.points)
    recon(splash_bin, FRAME, tmp_path / "plain.ply", "--attributes", "velocity")
    assert (tmp_path / "box.ply").read_bytes() == (tmp_path / "plain.ply").read_bytes()
    # A box around the lower half drops the rest, with their velocities.
    half = ",".join(repr(float(x)) for x in [*lo, hi[0], (lo[1] + hi[1]) / 2, hi[2]])
    r = recon(splash_bin, FRAME, tmp_path / "half.ply", "--particle-aabb", half,
              "--log-format", "json", "--attributes", "velocity")
    frame = next(json.loads(line) for line in r.stderr.splitlines() if '"frame"' in line)
    inside = (m.points[:, 1] <= (lo[1] + hi[1]) / 2).sum()
    assert frame["particles"] == inside
    assert frame["particles_outside_box"] == len(m.points) - inside


@pytest.mark.parametrize("ext", ["vtu", "vtk"])
def test_python_mesh_write_to_vtk_reads_back_with_its_arrays(tmp_path, ext):
    """Mesh.write to VTK files keeps what the arrays hold: read back by meshio (.vtu) or
    VTK's legacy reader (.vtk), bit for bit."""
    import splash_sph

    frame = splash_sph.read_particles(FRAME)
    mesh = splash_sph.reconstruct(
        frame.positions, spacing=FRAME_SPACING,
        attributes={"velocity": frame.attributes["velocity"]},
    )
    path = tmp_path / f"m.{ext}"
    mesh.write(path)
    if ext == "vtu":
        m = meshio.read(path)
        points, triangles = m.points, m.cells_dict["triangle"]
        normals, velocity = m.point_data["Normals"], m.point_data["velocity"]
    else:
        vtk = pytest.importorskip("vtk")
        from vtk.util.numpy_support import vtk_to_numpy

        reader = vtk.vtkPolyDataReader()
        reader.SetFileName(str(path))
        reader.Update()
        out = reader.GetOutput()
        points = vtk_to_numpy(out.GetPoints().GetData())
        triangles = vtk_to_numpy(out.GetPolys().GetConnectivityArray()).reshape(-1, 3)
        normals = vtk_to_numpy(out.GetPointData().GetArray("Normals"))
        velocity = vtk_to_numpy(out.GetPointData().GetArray("velocity"))
    assert len(mesh.faces) > 100_000
    assert same(points, mesh.vertices)
    assert np.array_equal(triangles, mesh.faces)
    assert same(normals, mesh.normals)
    assert same(velocity, mesh.attributes["velocity"])
