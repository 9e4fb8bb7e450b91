"""OpenVDB level sets from Python: ``level_set`` gives the signed distance at the active voxels
(negative inside, zero at the mesh), ``write_vdb`` writes it with attribute grids, and OpenVDB's
own ``vdb_print`` reads the file back (skipped without Debian's libopenvdb-tools)."""

import shutil
import subprocess

import numpy as np
import pytest

import splash_sph


def ball(r=0.01, radius=0.08):
    k = np.arange(-10, 11)
    grid = np.stack(np.meshgrid(k, k, k, indexing="ij"), -1).reshape(-1, 3) * r
    return grid[np.linalg.norm(grid, axis=1) <= radius].astype(np.float32), r


def test_level_set_is_the_signed_distance_of_the_mesh():
    particles, r = ball()
    mesh = splash_sph.reconstruct(particles, spacing=r, cell="r/2")
    voxel = r / 2
    ls = splash_sph.level_set(mesh, voxel)
    assert ls.voxel == pytest.approx(voxel) and ls.half_width == pytest.approx(3 * voxel)
    assert ls.ijk.dtype == np.int32 and ls.ijk.shape == (len(ls.values), 3)
    assert np.all(np.abs(ls.values) < ls.half_width)
    # Inside the ball negative, outside positive, by the distance from the centre.
    radius = np.linalg.norm(mesh.vertices, axis=1).mean()
    distance = np.linalg.norm(ls.ijk * voxel, axis=1) - radius
    assert np.all(np.sign(ls.values[np.abs(distance) > voxel]) == np.sign(distance[np.abs(distance) > voxel]))
    assert np.abs(ls.values - distance).max() < voxel
    # The same from a (vertices, faces) pair.
    again = splash_sph.level_set((mesh.vertices, mesh.faces), voxel)
    assert np.array_equal(again.ijk, ls.ijk) and np.array_equal(again.values, ls.values)


def test_write_vdb_with_grids_and_bad_input(tmp_path):
    particles, r = ball()
    mesh = splash_sph.reconstruct(particles, spacing=r, cell="r")
    ls = splash_sph.level_set(mesh, r)
    n = len(ls.values)
    path = tmp_path / "ball.vdb"
    speed = np.linalg.norm(ls.ijk, axis=1).astype(np.float32)
    splash_sph.write_vdb(path, mesh, r, grids={"velocity": np.ones((n, 3), np.float32), "speed": speed})
    assert path.read_bytes()[:4] == b" BDV"
    with pytest.raises(ValueError, match="active voxels"):
        splash_sph.write_vdb(tmp_path / "short.vdb", mesh, r, grids={"speed": speed[1:]})
    with pytest.raises(ValueError, match="voxel size"):
        splash_sph.level_set(mesh, 0.0)
    with pytest.raises(OSError, match="blocker"):
        (tmp_path / "blocker").write_text("a file")
        splash_sph.write_vdb(tmp_path / "blocker" / "x.vdb", mesh, r)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ball.vdb", "blocker"]
    if shutil.which("vdb_print") is None:
        pytest.skip("vdb_print not installed (apt-get install libopenvdb-tools)")
    listing = subprocess.run(["vdb_print", "-l", str(path)], capture_output=True, text=True, check=True).stdout
    for expected in ["Name: surface", "class: level set", "Name: v", "Name: speed", f"file_voxel_count: {n}"]:
        assert expected in listing, listing


def test_mesh_write_vdb_is_write_vdb_at_the_cell(tmp_path):
    """``Mesh.write`` of a ``.vdb`` path writes the level set on the reconstruction's cell, the
    same bytes as ``write_vdb`` at that voxel; a mesh without a cell needs ``voxel=``."""
    particles, r = ball()
    mesh = splash_sph.reconstruct(particles, spacing=r, cell="r/2")
    mesh.write(tmp_path / "ball.vdb")
    splash_sph.write_vdb(tmp_path / "direct.vdb", mesh, r / 2)
    assert (tmp_path / "ball.vdb").read_bytes() == (tmp_path / "direct.vdb").read_bytes()
    mesh.write(tmp_path / "coarse.dat", format="vdb", voxel=r)
    splash_sph.write_vdb(tmp_path / "coarse.vdb", mesh, r)
    assert (tmp_path / "coarse.dat").read_bytes() == (tmp_path / "coarse.vdb").read_bytes()
    alone = splash_sph.postprocess((mesh.vertices, mesh.faces), spacing=r)
    with pytest.raises(ValueError, match="voxel="):
        alone.write(tmp_path / "alone.vdb")
    assert not (tmp_path / "alone.vdb").exists()
