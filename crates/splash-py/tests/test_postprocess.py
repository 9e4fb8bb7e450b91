"""postprocess on any closed mesh: the reconstruction's bytes given its particles, each part's
own volume without them, smoother, and the box, small parts and decimation as asked."""

import types

import numpy as np
import pytest

import splash_sph
from conftest import FRAME_SPACING, ball

R = 0.1


def icosphere(subdivisions, radius=1.0, centre=(0.0, 0.0, 0.0)):
    """The icosahedron's faces split in four `subdivisions` times, on a sphere; outward."""
    t = (1 + 5**0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    vertices = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(subdivisions):
        middle, faces = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in middle:
                p = vertices[a] + vertices[b]
                vertices.append(p / np.linalg.norm(p))
                middle[key] = len(vertices) - 1
            return middle[key]

        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = faces
    vertices = np.array(vertices) * radius + np.asarray(centre)
    return vertices.astype(np.float32), np.array(f, dtype=np.uint32)


def noisy(vertices, amplitude, seed=1):
    """Each vertex moved along its radius by a uniform random amount up to `amplitude`."""
    rng = np.random.default_rng(seed)
    centre = vertices.mean(axis=0)
    d = vertices - centre
    n = d / np.linalg.norm(d, axis=1, keepdims=True)
    return (vertices + n * rng.uniform(-amplitude, amplitude, (len(vertices), 1))).astype(
        np.float32
    )


def volume(vertices, faces):
    a, b, c = (vertices[faces[:, k]].astype(np.float64) for k in range(3))
    return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0


def components(faces, n):
    """The component of each vertex (union-find over the triangles' corners)."""
    parent = np.arange(n)

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for a, b, c in faces:
        for u in (b, c):
            ra, ru = find(a), find(u)
            if ra != ru:
                parent[ru] = ra
    return np.array([find(v) for v in range(n)])


def assert_closed(faces):
    """Every directed edge once, and its reverse once: closed, manifold, consistently wound."""
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    keys = set(map(tuple, directed.tolist()))
    assert len(keys) == len(directed), "an edge walked twice the same way"
    assert all((b, a) in keys for a, b in keys), "a boundary edge"


def bumpiness(vertices, faces):
    """Area-weighted mean angle (degrees) between the normals of two faces sharing an edge."""
    v = vertices.astype(np.float64)
    cross = np.cross(v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]])
    area = np.linalg.norm(cross, axis=1) / 2
    normal = cross / np.linalg.norm(cross, axis=1, keepdims=True)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    owner = np.tile(np.arange(len(faces)), 3)
    key = np.sort(edges, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    a, b = owner[order[0::2]], owner[order[1::2]]
    angle = np.degrees(np.arccos(np.clip((normal[a] * normal[b]).sum(axis=1), -1, 1)))
    weight = area[a] + area[b]
    return (angle * weight).sum() / weight.sum()


def point_triangle_distance(points, triangles):
    """Exact distance from each point to the nearest of `triangles` (T, 3, 3)."""
    a, b, c = (triangles[:, k][None].astype(np.float64) for k in range(3))
    out = []
    for chunk in np.array_split(points.astype(np.float64), max(1, len(points) // 64)):
        p = chunk[:, None]
        n = np.cross(b - a, c - a)
        n = n / np.linalg.norm(n, axis=2, keepdims=True)
        h = ((p - a) * n).sum(axis=2)
        q = p - h[..., None] * n
        # Inside when q lies left of every edge (seen along the normal).
        inside = np.ones(h.shape, bool)
        for u, w in ((a, b), (b, c), (c, a)):
            inside &= (np.cross(w - u, q - u) * n).sum(axis=2) >= 0
        best = np.where(inside, np.abs(h), np.inf)
        for u, w in ((a, b), (b, c), (c, a)):
            e = w - u
            s = np.clip(((p - u) * e).sum(axis=2) / (e * e).sum(axis=2), 0, 1)
            best = np.minimum(best, np.linalg.norm(p - (u + s[..., None] * e), axis=2))
        out.append(best.min(axis=1))
    return np.concatenate(out)


def test_with_its_particles_the_raw_mesh_becomes_reconstructs_default_bit_for_bit(frame):
    droplets = np.array([[2.0, 0, 0], [0, 2.0, 0], [0, 0, 2.0], [R, 0, 2.0]], np.float32)
    x = np.concatenate([ball(R, 0.6), droplets])
    # Positions as an array, and a real frame as the Particles read_particles gives.
    for positions, r, particles in ((x, R, x), (frame.positions, FRAME_SPACING, frame)):
        raw = splash_sph.reconstruct(positions, r, raw=True)
        default = splash_sph.reconstruct(positions, r)
        post = splash_sph.postprocess(raw, particles=particles, threads=1)
        np.testing.assert_array_equal(post.vertices, default.vertices)
        np.testing.assert_array_equal(post.faces, default.faces)
        np.testing.assert_array_equal(post.normals, default.normals)
        # The spacing and cell came from the raw mesh's report; the raw mesh is unchanged.
        assert post.report["spacing"] == r and post.report["cell"] == raw.report["cell"]
        assert not np.array_equal(raw.vertices, default.vertices)


def test_particles_give_each_part_their_volume():
    x = ball(R, 0.8)
    raw = splash_sph.reconstruct(x, R, raw=True)
    target = len(x) * R**3
    assert abs(volume(raw.vertices, raw.faces) / target - 1) > 0.05
    post = splash_sph.postprocess((raw.vertices, raw.faces), particles=x, spacing=R)
    assert abs(volume(post.vertices, post.faces) / target - 1) < 0.01
    assert post.normals.shape == (0, 3)


def test_without_particles_each_closed_part_keeps_its_volume_and_gets_smoother():
    big_v, big_f = icosphere(4, 1.0)
    small_v, small_f = icosphere(3, 0.4, (3.0, 0, 0))
    vertices = noisy(np.concatenate([big_v, small_v]), 0.02)
    faces = np.concatenate([big_f, small_f + len(big_v)])
    label = components(faces, len(vertices))
    post = splash_sph.postprocess((vertices, faces.astype(np.int64)), spacing=R)
    assert post.faces.shape == faces.shape and post.faces.dtype == np.uint32
    assert_closed(post.faces)
    for part in np.unique(label):
        keep = label[faces[:, 0]] == part
        before = volume(vertices, faces[keep])
        after = volume(post.vertices, post.faces[keep])
        assert abs(after / before - 1) < 1e-6, (part, before, after)
    assert bumpiness(post.vertices, post.faces) < 0.5 * bumpiness(vertices, faces)
    # The mesh came as arrays: they are left alone.
    assert not np.array_equal(post.vertices, vertices)


def test_decimate_keeps_every_vertex_within_its_distance_of_the_full_surface():
    vertices, faces = icosphere(4, 1.0)
    full = splash_sph.postprocess((vertices, faces), spacing=R)
    light = splash_sph.postprocess((vertices, faces), spacing=R, decimate="0.1r")
    assert len(light.faces) < 0.5 * len(full.faces)
    assert_closed(light.faces)
    distance = point_triangle_distance(light.vertices, full.vertices[full.faces])
    assert distance.max() <= 0.1 * R * (1 + 1e-4), distance.max()
    # The decimation is measured against the smoothed mesh it decimates: 0.1 r as a number.
    same = splash_sph.postprocess((vertices, faces), spacing=R, decimate=0.1 * R)
    np.testing.assert_array_equal(same.faces, light.faces)


def test_min_component_drops_the_small_ball_and_keeps_the_big_one():
    big_v, big_f = icosphere(3, 1.0)
    small_v, small_f = icosphere(2, 0.2, (3.0, 0, 0))
    mesh = (np.concatenate([big_v, small_v]), np.concatenate([big_f, small_f + len(big_v)]))
    # 4/3 π 0.2³ = 0.034 = 33 r³ and 4.2 = 4189 r³.
    kept = splash_sph.postprocess(mesh, spacing=R, min_component=1000)
    assert len(np.unique(components(kept.faces, len(kept.vertices)))) == 1
    assert kept.vertices[:, 0].max() < 1.1
    assert_closed(kept.faces)
    both = splash_sph.postprocess(mesh, spacing=R, min_component=20)
    assert len(both.faces) == len(mesh[1])


def test_mesh_aabb_clips_and_caps_so_the_mesh_stays_closed():
    vertices, faces = icosphere(4, 1.0)
    whole = splash_sph.postprocess((vertices, faces), spacing=R)
    half = splash_sph.postprocess((vertices, faces), spacing=R, mesh_aabb=[-2, -2, -2, 0, 2, 2])
    assert_closed(half.faces)
    assert half.vertices[:, 0].max() <= 1e-4
    ratio = volume(half.vertices, half.faces) / volume(whole.vertices, whole.faces)
    assert abs(ratio - 0.5) < 0.01, ratio


def test_every_kind_of_mesh_is_taken_and_attributes_ride_along_while_vertices_stay(tmp_path):
    x = ball(R, 0.6)
    velocity = np.tile(np.float32([1, 2, 3]), (len(x), 1))
    raw = splash_sph.reconstruct(x, R, raw=True, attributes={"velocity": velocity})
    smooth = splash_sph.postprocess(raw)
    assert smooth.attributes["velocity"].shape == (len(smooth.vertices), 3)
    light = splash_sph.postprocess(raw, decimate="0.1r")
    assert light.attributes == {}
    raw.write(tmp_path / "raw.ply")
    arrays = splash_sph.read_mesh(tmp_path / "raw.ply")
    namespace = types.SimpleNamespace(vertices=raw.vertices, faces=raw.faces.astype(np.int32))
    for mesh in (arrays, namespace):
        other = splash_sph.postprocess(mesh, spacing=R)
        np.testing.assert_array_equal(other.faces, smooth.faces)
    assert len(splash_sph.postprocess(arrays, spacing=R).normals) == len(smooth.vertices)
    assert len(splash_sph.postprocess(namespace, spacing=R).normals) == 0


def test_post_settings_and_the_config_are_read():
    vertices, faces = icosphere(3, 1.0)
    vertices = noisy(vertices, 0.03)
    same = splash_sph.postprocess((vertices, faces), spacing=R, raw=True)
    np.testing.assert_array_equal(same.vertices, vertices)
    light = splash_sph.postprocess((vertices, faces), spacing=R, smoothing_iterations=1,
                                   volume_rounds=0, relax_iterations=0, volume_steps=0)
    strong = splash_sph.postprocess((vertices, faces), config={"spacing": R},
                                    smoothing_iterations=40, lambda_=0.6, mu=-0.62)
    assert bumpiness(strong.vertices, strong.faces) < bumpiness(light.vertices, light.faces)
    by_dict = splash_sph.postprocess(
        (vertices, faces), config={"spacing": R, "post": {"smoothing_iterations": 40,
                                                          "lambda": 0.6, "mu": -0.62}})
    np.testing.assert_array_equal(by_dict.vertices, strong.vertices)
    unrelaxed = splash_sph.postprocess((vertices, faces), spacing=R, relax_first=0)
    relaxed = splash_sph.postprocess((vertices, faces), spacing=R)
    assert not np.array_equal(unrelaxed.vertices, relaxed.vertices)
    by_dict = splash_sph.postprocess((vertices, faces),
                                     config={"spacing": R, "post": {"relax_first": 0}})
    np.testing.assert_array_equal(by_dict.vertices, unrelaxed.vertices)


def test_bad_meshes_and_settings_raise_value_error_naming_what_is_wrong():
    vertices, faces = icosphere(2, 1.0)
    cases = [
        ((vertices, faces[:-1]), {}, "3 boundary edges"),
        ((vertices, np.concatenate([faces, faces[:1]])), {}, "3 non-manifold edges"),
        ((vertices, np.concatenate([faces[:1, ::-1], faces[1:]])), {}, "3 edges whose two"),
        ((vertices, np.where(faces == 5, len(vertices), faces)), {}, "references vertex"),
        ((vertices, faces.astype(np.int64) - 1), {}, "vertex index -1"),
        ((np.where(np.arange(len(vertices))[:, None] == 3, np.nan, vertices), faces), {},
         "vertex 3 is not finite"),
        ((vertices, faces.astype(np.float32)), {}, "integer vertex indices"),
        ((vertices, faces[:, :2]), {}, "shape (F, 3)"),
        ((vertices[:, :2], faces), {}, "shape (N, 3)"),
        ((vertices, faces), {"mu": -0.1}, "post.mu"),
        ((vertices, faces), {"volume_steps": -1}, "volume_steps must be a count from 0, got -1"),
        ((vertices, faces), {"relax_first": -2}, "relax_first must be a count from 0, got -2"),
        ((vertices, faces), {"mesh_aabb": [0, 0, 0, 1, 1]}, "six numbers"),
        ((vertices, faces), {"particles": np.full((1, 3), np.inf, np.float32)}, "particle 0"),
    ]
    for mesh, kwargs, message in cases:
        kwargs.setdefault("spacing", R)
        with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
            splash_sph.postprocess(mesh, **kwargs)
    with pytest.raises(ValueError, match="spacing is not set"):
        splash_sph.postprocess((vertices, faces))
    with pytest.raises(TypeError, match="mesh must be"):
        splash_sph.postprocess(vertices)


def test_reconstruct_times_the_post_stage_and_raw_skips_it():
    x = ball(R, 0.6)
    stages = ("handler_array", "surface_particles", "band", "scalar_field", "triangulation",
              "post")
    for raw in (False, True):
        t = splash_sph.reconstruct(x, R, raw=raw).report["times"]
        assert all(t[k] >= 0 for k in stages)
        assert sum(t[k] for k in stages) == pytest.approx(t["reconstruction"], rel=1e-9)
        assert t["post"] <= t["reconstruction"] <= t["total"]
        assert (t["post"] == 0) == raw, t
    # Asked for on a raw mesh, the box is post-processing too.
    boxed = splash_sph.reconstruct(x, R, raw=True, mesh_aabb=[-1, -1, -1, 0, 1, 1])
    assert boxed.report["times"]["post"] > 0
