"""The Python package makes the CLI's meshes, byte for byte."""

import subprocess

import numpy as np

import splash_sph
from conftest import FRAME, FRAME_SPACING, read_obj, read_ply_columns


def recon(splash_bin, output, *flags):
    subprocess.run(
        [splash_bin, "recon", FRAME, "--spacing", str(FRAME_SPACING), "-q", "-o", output, *flags],
        check=True,
    )


def test_mesh_and_obj_equal_the_cli(frame, splash_bin, tmp_path):
    recon(splash_bin, tmp_path / "y.obj")
    mesh = splash_sph.reconstruct(frame.positions, spacing=FRAME_SPACING)
    vertices, faces = read_obj(tmp_path / "y.obj")
    assert mesh.vertices.shape[0] > 1000
    np.testing.assert_array_equal(mesh.vertices, vertices)
    np.testing.assert_array_equal(mesh.faces, faces)
    mesh.write(tmp_path / "x.obj")
    assert (tmp_path / "x.obj").read_bytes() == (tmp_path / "y.obj").read_bytes()


def test_velocities_and_ply_equal_the_cli(frame, splash_bin, tmp_path):
    recon(splash_bin, tmp_path / "y.ply", "--attributes", "velocity", "--up-axis", "z")
    columns = read_ply_columns(FRAME)
    velocity = np.stack([columns["vx"], columns["vy"], columns["vz"]], axis=1)
    mesh = splash_sph.reconstruct(
        frame.positions, spacing=FRAME_SPACING, attributes={"velocity": velocity}
    )
    assert mesh.attributes["velocity"].shape == mesh.vertices.shape
    mesh.write(tmp_path / "x.ply", up_axis="z")
    assert (tmp_path / "x.ply").read_bytes() == (tmp_path / "y.ply").read_bytes()


def test_read_particles_gives_the_files_attributes(frame):
    """The fixture's vertex properties: x y z vx vy vz density, as an independent reader sees
    them; the velocities straight from read_particles give the CLI's mesh attributes."""
    columns = read_ply_columns(FRAME)
    assert sorted(frame.attributes) == ["density", "velocity"]
    assert "velocity" in frame and len(frame) == len(columns["x"])
    velocity = frame["velocity"]
    assert velocity.shape == (len(frame), 3) and velocity.dtype == np.float32
    np.testing.assert_array_equal(velocity[:, 0], columns["vx"])
    np.testing.assert_array_equal(velocity[:, 2], columns["vz"])
    np.testing.assert_array_equal(frame["density"], columns["density"])
    np.testing.assert_array_equal(frame.positions[:, 1], columns["y"])
    mesh = splash_sph.reconstruct(
        frame.positions, spacing=FRAME_SPACING, attributes={"velocity": frame["velocity"]}
    )
    by_hand = splash_sph.reconstruct(
        frame.positions,
        spacing=FRAME_SPACING,
        attributes={"velocity": np.stack([columns[c] for c in ("vx", "vy", "vz")], axis=1)},
    )
    np.testing.assert_array_equal(mesh.attributes["velocity"], by_hand.attributes["velocity"])
