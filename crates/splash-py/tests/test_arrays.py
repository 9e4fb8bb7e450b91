"""numpy in and out: dtypes, memory orders, views, shapes, non-finite values, no copies out."""

import numpy as np
import pytest

import splash_sph
from conftest import FRAME_SPACING, ball

SPACING = 0.1


@pytest.fixture(scope="module")
def particles():
    return ball(SPACING)


@pytest.fixture(scope="module")
def reference(particles):
    return splash_sph.reconstruct(particles, spacing=SPACING)


def strided_rows(x):
    """`x` as every other row of a larger array (a non-contiguous view)."""
    big = np.full((2 * len(x), 3), 1e3, dtype=x.dtype)
    big[::2] = x
    return big[::2]


def strided_columns(x):
    """`x` as every other column of a wider array."""
    wide = np.full((len(x), 6), -1e3, dtype=x.dtype)
    wide[:, ::2] = x
    return wide[:, ::2]


@pytest.mark.parametrize(
    "variant",
    [
        lambda x: x.astype(np.float64),
        np.asfortranarray,
        lambda x: np.asfortranarray(x.astype(np.float64)),
        strided_rows,
        strided_columns,
        lambda x: strided_rows(x.astype(np.float64)),
        lambda x: x.astype(">f4"),
        lambda x: x.astype(np.longdouble),
        lambda x: x.tolist(),
    ],
    ids=[
        "f64",
        "f32-F",
        "f64-F",
        "f32-rows",
        "f32-columns",
        "f64-rows",
        "f32-big-endian",
        "longdouble",
        "list",
    ],
)
def test_every_layout_gives_the_same_mesh(particles, reference, variant):
    x = variant(particles)
    mesh = splash_sph.reconstruct(x, spacing=SPACING)
    assert len(mesh.faces) > 100
    np.testing.assert_array_equal(mesh.vertices, reference.vertices)
    np.testing.assert_array_equal(mesh.faces, reference.faces)


def test_output_arrays(reference):
    v, f, n = reference.vertices, reference.faces, reference.normals
    assert v.dtype == np.float32 and v.ndim == 2 and v.shape[1] == 3 and v.flags.c_contiguous
    assert f.dtype == np.uint32 and f.shape[1] == 3 and f.max() < len(v)
    assert n.dtype == np.float32 and n.shape == v.shape
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
    # Normals point out of the ball.
    assert (np.einsum("ij,ij->i", n, v) > 0).all()


def test_outputs_own_the_library_memory(reference):
    """The arrays wrap the library's buffers: numpy did not allocate (copy into) them."""
    for a in (reference.vertices, reference.faces, reference.normals):
        assert not a.flags.owndata
        assert not isinstance(a.base, np.ndarray)


def test_edges_are_the_faces_distinct_sides(reference):
    """Checked against numpy's own unique edges: each corner points to the edge from its
    vertex to the next corner's, every edge is walked twice on the closed mesh."""
    f = reference.faces
    edges, corner_edges = splash_sph.mesh_edges(f, len(reference.vertices))
    assert edges.dtype == np.uint32 and edges.shape == (3 * len(f) // 2, 2)
    assert corner_edges.dtype == np.uint32 and corner_edges.shape == (3 * len(f),)
    sides = np.stack([f.ravel(), np.roll(f, -1, axis=1).ravel()], axis=1)
    expected = np.unique(np.sort(sides, axis=1), axis=0)
    np.testing.assert_array_equal(np.unique(edges, axis=0), expected)
    np.testing.assert_array_equal(edges[corner_edges], np.sort(sides, axis=1))
    assert (np.bincount(corner_edges) == 2).all()
    # A face beyond the vertices, or faces not uint32 rows of three, are refused.
    bad = f.copy()
    bad[3, 1] = len(reference.vertices)
    with pytest.raises(ValueError, match="triangle 3"):
        splash_sph.mesh_edges(bad, len(reference.vertices))
    with pytest.raises(ValueError, match="faces"):
        splash_sph.mesh_edges(f.astype(np.int64), len(reference.vertices))


def test_normals_none(particles):
    mesh = splash_sph.reconstruct(particles, spacing=SPACING, normals="none")
    assert mesh.normals.shape == (0, 3)
    assert len(mesh.vertices) > 0


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_empty_input_gives_an_empty_mesh(dtype):
    mesh = splash_sph.reconstruct(np.zeros((0, 3), dtype=dtype), spacing=SPACING)
    assert mesh.vertices.shape == (0, 3)
    assert mesh.faces.shape == (0, 3)
    assert mesh.normals.shape == (0, 3)
    assert mesh.report["particles"] == 0


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_non_finite_coordinates_are_refused(particles, bad, dtype):
    x = particles.astype(dtype)
    x[7, 1] = bad
    with pytest.raises(ValueError, match="particle 7 has a non-finite coordinate"):
        splash_sph.reconstruct(x, spacing=SPACING)


@pytest.mark.parametrize("shape", [(30,), (30, 2), (30, 4), (10, 3, 1), ()])
def test_wrong_shapes_are_refused(shape):
    with pytest.raises(ValueError, match=r"positions must be an array of shape \(N, 3\)"):
        splash_sph.reconstruct(np.zeros(shape, dtype=np.float32), spacing=SPACING)


@pytest.mark.parametrize("dtype", [np.int64, np.int32, np.uint8, np.bool_, np.complex64, object])
def test_other_dtypes_are_refused(particles, dtype):
    with pytest.raises(ValueError, match="positions must hold floating-point values, got"):
        splash_sph.reconstruct(particles.astype(dtype), spacing=SPACING)


def test_estimate_spacing(frame, particles):
    r = splash_sph.estimate_spacing(frame.positions)
    assert r == pytest.approx(FRAME_SPACING, rel=0.02)
    assert splash_sph.estimate_spacing(frame.positions.astype(np.float64)) == r
    with pytest.raises(ValueError, match="cannot estimate the particle spacing from 1 particles"):
        splash_sph.estimate_spacing(particles[:1])
