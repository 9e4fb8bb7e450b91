"""Per-particle attributes interpolated onto the vertices, as the CLI's velocities."""

import numpy as np
import pytest

import splash_sph
from conftest import ball, read_ply_columns

SPACING = 0.1


@pytest.fixture(scope="module")
def particles():
    return ball(SPACING, radius=0.8)


def test_a_constant_field_interpolates_to_itself(particles):
    constant = np.array([1.5, -2.0, 0.25], dtype=np.float32)
    velocity = np.tile(constant, (len(particles), 1))
    mesh = splash_sph.reconstruct(particles, spacing=SPACING, attributes={"velocity": velocity})
    v = mesh.attributes["velocity"]
    assert v.shape == mesh.vertices.shape and v.dtype == np.float32
    np.testing.assert_allclose(v, np.broadcast_to(constant, v.shape), rtol=1e-5)


@pytest.mark.parametrize("field", ["zb05", "density", "blobby", "metaball", "anisotropic"])
def test_every_fields_kernel_keeps_a_constant(particles, field):
    """Each field weighs the particles with its own kernel, normalised: constants stay."""
    density = np.full(len(particles), 997.5, dtype=np.float32)
    mesh = splash_sph.reconstruct(
        particles, spacing=SPACING, field=field, attributes={"density": density}
    )
    assert len(mesh.vertices) > 100
    np.testing.assert_allclose(mesh.attributes["density"], 997.5, rtol=1e-5)


def test_a_linear_field_interpolates_near_the_vertices(particles):
    """A rotation about z: each vertex gets about the velocity at its own position, as the
    weights sit within the support around it."""
    velocity = np.stack([-particles[:, 1], particles[:, 0], np.zeros(len(particles))], axis=1)
    mesh = splash_sph.reconstruct(particles, spacing=SPACING, attributes={"velocity": velocity})
    expected = np.stack([-mesh.vertices[:, 1], mesh.vertices[:, 0]], axis=1)
    error = np.abs(mesh.attributes["velocity"][:, :2] - expected).max()
    # Exact in the interior; at the surface the weights are one-sided, pulling inwards.
    assert error < 2 * SPACING


def test_scalars_interpolate_like_a_vector_component(particles):
    density = np.linspace(900.0, 1100.0, len(particles))
    vector = np.stack([density, density, density], axis=1)
    mesh = splash_sph.reconstruct(
        particles, spacing=SPACING, attributes={"density": density, "vector": vector}
    )
    d = mesh.attributes["density"]
    assert d.shape == (len(mesh.vertices),) and d.dtype == np.float32
    np.testing.assert_allclose(d, mesh.attributes["vector"][:, 0], rtol=1e-6)
    assert d.min() >= 900.0 and d.max() <= 1100.0 and d.std() > 1.0


def test_wrong_attributes_are_refused(particles):
    with pytest.raises(ValueError, match=r"attributes\['velocity'\] has 3 values for"):
        splash_sph.reconstruct(
            particles, spacing=SPACING, attributes={"velocity": np.zeros((3, 3))}
        )
    with pytest.raises(ValueError, match=r"attributes\['velocity'\] must be an array of shape"):
        splash_sph.reconstruct(
            particles, spacing=SPACING, attributes={"velocity": np.zeros((len(particles), 2))}
        )
    with pytest.raises(TypeError, match="attributes must be a dict"):
        splash_sph.reconstruct(particles, spacing=SPACING, attributes=[1])


def test_velocities_are_written_to_ply_only(particles, tmp_path):
    velocity = np.tile(np.float32([1, 2, 3]), (len(particles), 1))
    with_v = splash_sph.reconstruct(particles, spacing=SPACING, attributes={"velocity": velocity})
    plain = splash_sph.reconstruct(particles, spacing=SPACING)
    with_v.write(tmp_path / "v.ply")
    columns = read_ply_columns(tmp_path / "v.ply")
    np.testing.assert_array_equal(columns["x"], with_v.vertices[:, 0])
    np.testing.assert_allclose(columns["vz"], 3.0, rtol=1e-5)
    # OBJ has no place for them.
    with_v.write(tmp_path / "v.obj")
    plain.write(tmp_path / "plain.obj")
    assert (tmp_path / "v.obj").read_bytes() == (tmp_path / "plain.obj").read_bytes()
