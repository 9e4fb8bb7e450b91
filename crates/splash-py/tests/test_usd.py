"""USD output read by Pixar's own library (usd-core): the CLI's sequence stage plays frame t's
mesh at time t (points, faces, normals and velocities exactly the PLY's of the same frame),
recon_sequence writes the same layers, and a failed frame is left out of the stage until a
later run writes it. Skips, saying why, where usd-core is not installed."""

import shutil
import subprocess

import numpy as np
import pytest

import splash_sph
from conftest import FRAME, FRAME_SPACING, REPO, read_ply_columns

pxr = pytest.importorskip("pxr", reason="usd-core is not installed (pip install usd-core)")
from pxr import Usd, UsdGeom  # noqa: E402

FRAMES = [REPO / "fixtures" / "frame_0010.ply", FRAME]


def recon(splash_bin, inputs, output, *flags):
    return subprocess.run(
        [splash_bin, "recon", *inputs, "--spacing", str(FRAME_SPACING), "-o", output, *flags],
        capture_output=True,
        text=True,
    )


def sequence(tmp_path):
    sim = tmp_path / "sim"
    sim.mkdir()
    for f in FRAMES:
        shutil.copy(f, sim / f.name)
    return sim


def mesh_at(stage, time):
    """Points, faces (F, 3), normals and velocities of /Surface at `time`, as numpy arrays."""
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Surface"))
    get = lambda attr: np.array(attr.Get(time), dtype=np.float32)  # noqa: E731
    counts = np.array(mesh.GetFaceVertexCountsAttr().Get(time))
    assert (counts == 3).all()
    faces = np.array(mesh.GetFaceVertexIndicesAttr().Get(time), dtype=np.uint32).reshape(-1, 3)
    return (
        get(mesh.GetPointsAttr()),
        faces,
        get(mesh.GetNormalsAttr()),
        get(mesh.GetVelocitiesAttr()),
        mesh,
    )


def ply_frame(path):
    """Vertices, faces, normals and velocities of a binary PLY the CLI wrote with velocities."""
    columns = read_ply_columns(path)
    data = path.read_bytes()
    header = data[: data.index(b"end_header\n")].decode()
    faces_count = int(header.split("element face ")[1].split()[0])
    vertex_bytes = 4 * len(columns) * len(columns["x"])
    offset = data.index(b"end_header\n") + len(b"end_header\n") + vertex_bytes
    records = np.frombuffer(
        data, dtype=[("n", "u1"), ("i", "<u4", 3)], count=faces_count, offset=offset
    )
    assert (records["n"] == 3).all()
    stack = lambda *names: np.stack([columns[n] for n in names], axis=1)  # noqa: E731
    return (
        stack("x", "y", "z"),
        records["i"],
        stack("nx", "ny", "nz"),
        stack("vx", "vy", "vz"),
    )


def test_the_stage_plays_each_frames_mesh_at_its_time(splash_bin, tmp_path):
    sim = sequence(tmp_path)
    usd, ply = tmp_path / "usd", tmp_path / "ply"
    run = recon(splash_bin, [sim], f"{usd}/", "--format", "usd")
    assert run.returncode == 0, run.stderr
    run = recon(splash_bin, [sim], f"{ply}/", "--format", "ply", "--attributes", "velocity")
    assert run.returncode == 0, run.stderr
    stage = Usd.Stage.Open(str(usd / "frame.usda"))
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (10, 40)
    assert stage.GetTimeCodesPerSecond() == 24 and UsdGeom.GetStageMetersPerUnit(stage) == 1
    counts = []
    for time, name in [(10, "frame_0010.ply"), (40, "frame_0040.ply")]:
        points, faces, normals, velocities, mesh = mesh_at(stage, time)
        expected = ply_frame(ply / name)
        for got, want in zip((points, faces, normals, velocities), expected):
            assert got.shape == want.shape and got.shape[0] > 1000
            np.testing.assert_array_equal(got, want)
        assert mesh.GetNormalsInterpolation() == UsdGeom.Tokens.vertex
        assert mesh.GetSubdivisionSchemeAttr().Get() == UsdGeom.Tokens.none
        assert mesh.GetOrientationAttr().Get() == UsdGeom.Tokens.rightHanded
        valid, why = UsdGeom.Mesh.ValidateTopology(
            faces.reshape(-1).tolist(), [3] * len(faces), len(points)
        )
        assert valid, why
        extent = np.array(mesh.GetExtentAttr().Get(time), dtype=np.float32)
        np.testing.assert_array_equal(extent, [points.min(axis=0), points.max(axis=0)])
        counts.append(len(points))
    assert counts[0] != counts[1]
    # Between two frames the earlier one holds.
    assert len(mesh_at(stage, 25)[0]) == counts[0]
    # Outward triangles: the mesh's signed volume is positive in the right-handed frame.
    points, faces = mesh_at(stage, 40)[:2]
    a, b, c = (points[faces[:, k]].astype(np.float64) for k in range(3))
    assert np.einsum("ij,ij->i", a, np.cross(b, c)).sum() > 0

    # recon_sequence writes the same files.
    again = tmp_path / "py"
    report = splash_sph.recon_sequence(sim, f"{again}/", format="usd", spacing=FRAME_SPACING)
    assert report["ok"]
    for name in ["frame_0010.usda", "frame_0040.usda", "frame.usda", "frame.topology.usda"]:
        assert (again / name).read_bytes() == (usd / name).read_bytes(), name


def test_a_single_frame_is_one_layer(splash_bin, tmp_path):
    run = recon(splash_bin, [FRAME], tmp_path / "x.usda", "--up-axis", "z")
    assert run.returncode == 0, run.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.usda"]
    stage = Usd.Stage.Open(str(tmp_path / "x.usda"))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    # Sampled at the frame's number, held at every time.
    assert stage.GetStartTimeCode() == stage.GetEndTimeCode() == 40
    points, faces, normals, velocities, _ = mesh_at(stage, 40)
    assert len(mesh_at(stage, 1)[0]) == len(points)
    mesh = splash_sph.reconstruct(splash_sph.read_particles(FRAME).positions, spacing=FRAME_SPACING)
    mesh.write(tmp_path / "m.ply", up_axis="z")
    columns = read_ply_columns(tmp_path / "m.ply")
    np.testing.assert_array_equal(points, np.stack([columns[c] for c in "xyz"], axis=1))
    np.testing.assert_array_equal(faces, mesh.faces)
    assert len(velocities) == len(points)


def test_a_failed_frame_is_left_out_until_a_run_writes_it(splash_bin, tmp_path):
    sim = sequence(tmp_path)
    (sim / "frame_0070.ply").write_text("ply\nformat ascii 1.0\nelement vertex 2\n")
    usd = tmp_path / "usd"
    run = recon(splash_bin, [sim], f"{usd}/", "--format", "usd")
    assert run.returncode != 0 and "frame_0070" in run.stderr
    assert "leaves out frame 70" in run.stderr, run.stderr
    stage = Usd.Stage.Open(str(usd / "frame.usda"))
    assert stage.GetEndTimeCode() == 40
    # The layer registry would hand the old stage layer back while it is open.
    del stage
    shutil.copy(FRAMES[0], sim / "frame_0070.ply")
    run = recon(splash_bin, [sim], f"{usd}/", "--format", "usd", "--skip-existing")
    assert run.returncode == 0, run.stderr
    stage = Usd.Stage.Open(str(usd / "frame.usda"))
    assert stage.GetEndTimeCode() == 70
    assert len(mesh_at(stage, 70)[0]) == len(mesh_at(stage, 10)[0])
