"""splash_sph.iso: the CLI's isosurfaces byte for byte, an analytic level set, and errors."""

import subprocess
import warnings

import numpy as np
import pytest

import splash_sph
from conftest import FRAME, FRAME_SPACING, read_ply_columns


def cli_iso(splash_bin, output, *flags):
    subprocess.run(
        [splash_bin, "iso", FRAME, "--spacing", str(FRAME_SPACING), "--cell", "r", "-q",
         "-o", output, *flags],
        check=True,
    )


def test_density_isosurface_equals_the_cli(frame, splash_bin, tmp_path):
    cli_iso(splash_bin, tmp_path / "y.ply", "--attribute", "density", "--level", "1000",
            "--shepard")
    mesh = splash_sph.iso(frame, "density", 1000.0, spacing=FRAME_SPACING, cell="r",
                          shepard=True, threads=2)
    cli = read_ply_columns(tmp_path / "y.ply")
    assert mesh.vertices.shape[0] > 1000 and mesh.faces.shape[0] > 1000
    np.testing.assert_array_equal(mesh.vertices[:, 0], cli["x"])
    np.testing.assert_array_equal(mesh.vertices[:, 2], cli["z"])
    np.testing.assert_array_equal(mesh.normals[:, 1], cli["ny"])
    assert mesh.report["triangles"] == mesh.faces.shape[0]
    assert mesh.report["seed_cells"] > 0 and 0.0 <= mesh.report["cache_hit_ratio"] <= 1.0
    mesh.write(tmp_path / "x.ply")
    assert (tmp_path / "x.ply").read_bytes() == (tmp_path / "y.ply").read_bytes()
    back = splash_sph.read_mesh(tmp_path / "y.ply")
    np.testing.assert_array_equal(back.faces, mesh.faces)


def test_speed_isosurface_with_density_equals_the_cli(frame, splash_bin, tmp_path):
    cli_iso(splash_bin, tmp_path / "y.ply", "--attribute", "velocity", "--magnitude",
            "--level", "1.0", "--attributes", "density")
    mesh = splash_sph.iso(frame, "v", 1.0, magnitude=True, spacing=FRAME_SPACING, cell="r",
                          attributes=["density"])
    assert mesh.attributes["density"].shape == (mesh.vertices.shape[0],)
    mesh.write(tmp_path / "x.ply")
    assert (tmp_path / "x.ply").read_bytes() == (tmp_path / "y.ply").read_bytes()


def test_linear_field_gives_the_plane_x_equals_level():
    """A = x on a lattice symmetric in x about the plane x = c: with Shepard normalisation the
    interpolant is exactly c on that plane (the weights' first moment in x vanishes there), and
    the corrected vertices lie on it."""
    r, c = 0.1, 1.5
    axis_x = c + np.arange(-6, 7) * r
    axis_yz = np.arange(0, 8) * r
    grid = np.stack(np.meshgrid(axis_x, axis_yz, axis_yz, indexing="ij"), axis=-1).reshape(-1, 3)
    positions = grid.astype(np.float32)
    mesh = splash_sph.iso(positions, positions[:, 0].copy(), c, spacing=r, shepard=True,
                          correct=3)
    assert mesh.faces.shape[0] > 50
    np.testing.assert_allclose(mesh.vertices[:, 0], c, rtol=0, atol=1e-5 * c)
    # The normals point towards larger A: +x.
    assert np.all(mesh.normals[:, 0] > 0.99)


def test_unknown_attribute_lists_the_frames(frame):
    with pytest.raises(KeyError, match="pressure.*density, velocity"):
        splash_sph.iso(frame, "pressure", 1.0, spacing=FRAME_SPACING)


def test_vector_needs_magnitude_or_vorticity(frame):
    with pytest.raises(ValueError, match="vector attribute"):
        splash_sph.iso(frame, "velocity", 1.0, spacing=FRAME_SPACING)
    with pytest.raises(ValueError, match="exclude"):
        splash_sph.iso(frame, "velocity", 1.0, spacing=FRAME_SPACING, magnitude=True,
                       vorticity=True)


def test_bad_arguments():
    positions = np.zeros((4, 3), dtype=np.float32)
    with pytest.raises(ValueError, match="3 values for 4 particles"):
        splash_sph.iso(positions, np.zeros(3), 1.0, spacing=0.1)
    with pytest.raises(TypeError, match="array of per-particle values"):
        splash_sph.iso(positions, "density", 1.0, spacing=0.1)
    with pytest.raises(ValueError, match="spacing"):
        splash_sph.iso(positions, np.zeros(4), 1.0)
    with pytest.raises(ValueError, match="correct"):
        splash_sph.iso(positions, np.zeros(4), 1.0, spacing=0.1, correct=-1)


def test_vorticity_kernel_scale_and_correct_equal_the_cli(frame, splash_bin, tmp_path):
    cli_iso(splash_bin, tmp_path / "y.ply", "--attribute", "velocity", "--vorticity",
            "--level", "20", "--kernel-scale", "0.75", "--correct=0")
    mesh = splash_sph.iso(frame, "velocity", 20.0, vorticity=True, spacing=FRAME_SPACING,
                          cell="r", kernel_scale=0.75, correct=0)
    assert mesh.faces.shape[0] > 100 and mesh.report["correction"]["mean"] == 0.0
    mesh.write(tmp_path / "x.ply")
    assert (tmp_path / "x.ply").read_bytes() == (tmp_path / "y.ply").read_bytes()


def test_lambda2_equals_the_cli(frame, splash_bin, tmp_path):
    cli_iso(splash_bin, tmp_path / "y.ply", "--attribute", "velocity", "--lambda2",
            "--level", "-50")
    mesh = splash_sph.iso(frame, "velocity", -50.0, lambda2=True, spacing=FRAME_SPACING,
                          cell="r")
    assert mesh.faces.shape[0] > 100
    mesh.write(tmp_path / "x.ply")
    assert (tmp_path / "x.ply").read_bytes() == (tmp_path / "y.ply").read_bytes()
    with pytest.raises(ValueError, match="exclude"):
        splash_sph.iso(frame, "velocity", -50.0, spacing=FRAME_SPACING, vorticity=True,
                       lambda2=True)


def test_a_kernel_scale_leaving_few_neighbours_warns(frame):
    with pytest.warns(UserWarning, match="kernel scale 0.5"):
        small = splash_sph.iso(frame, "velocity", 1.5, magnitude=True, spacing=FRAME_SPACING,
                               cell="r", kernel_scale=0.5)
    assert small.report["support_neighbours"] < 10
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        full = splash_sph.iso(frame, "velocity", 1.5, magnitude=True, spacing=FRAME_SPACING,
                              cell="r")
    assert full.report["support_neighbours"] > 20
