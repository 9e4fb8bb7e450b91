use std::f32::consts::{PI, TAU};

use super::*;
use crate::data::TriMesh;
use crate::tests::common::{merged, torus, uniform};

/// A closed UV sphere, outward: `rings` bands of `segments` quads split in two, fans at the
/// poles (vertex 0 the north pole, the last the south pole).
fn sphere(centre: Vec3, radius: f32, rings: u32, segments: u32) -> TriMesh {
    let mut vertices = vec![centre + radius * Vec3::Z];
    for i in 1..rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = TAU * j as f32 / segments as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            vertices.push(centre + radius * d);
        }
    }
    vertices.push(centre - radius * Vec3::Z);
    let south = vertices.len() as u32 - 1;
    let at = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let mut triangles = Vec::new();
    for j in 0..segments {
        triangles.push([0, at(1, j), at(1, j + 1)]);
        for i in 1..rings - 1 {
            let (u, u1, l, l1) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            triangles.extend([[u, l, l1], [u, l1, u1]]);
        }
        triangles.push([south, at(rings - 1, j + 1), at(rings - 1, j)]);
    }
    TriMesh {
        vertices,
        normals: Vec::new(),
        triangles,
    }
}

fn found(m: &TriMesh) -> Vec<u32> {
    self_intersecting_faces(&m.vertices, &m.triangles)
}

fn soup(triangles: &[[f32; 9]]) -> TriMesh {
    TriMesh {
        vertices: triangles
            .iter()
            .flat_map(|t| t.chunks(3).map(Vec3::from_slice))
            .collect(),
        normals: Vec::new(),
        triangles: (0..triangles.len() as u32)
            .map(|f| [3 * f, 3 * f + 1, 3 * f + 2])
            .collect(),
    }
}

#[test]
fn a_closed_sphere_and_a_torus_do_not_cross_themselves() {
    assert!(found(&sphere(Vec3::ZERO, 1.0, 24, 48)).is_empty());
    assert!(found(&torus(48, 24, 1.0, 0.3, 0.5)).is_empty());
    // Apart in one mesh, nothing either.
    let two = merged(
        &sphere(Vec3::ZERO, 1.0, 16, 32),
        &sphere(Vec3::new(2.01, 0.0, 0.0), 1.0, 16, 32),
    );
    assert!(found(&two).is_empty());
}

#[test]
fn two_overlapping_spheres_in_one_mesh_are_found_where_they_cross() {
    let (a, b) = (
        sphere(Vec3::ZERO, 1.0, 16, 32),
        sphere(Vec3::new(1.2, 0.0, 0.0), 1.0, 16, 32),
    );
    let two = merged(&a, &b);
    let crossing = found(&two);
    let first = a.triangles.len() as u32;
    assert!(crossing.iter().any(|&f| f < first) && crossing.iter().any(|&f| f >= first));
    // The spheres cross on the circle x = 0.6, radius 0.8: every face found reaches it.
    for &f in &crossing {
        let t = two.triangles[f as usize].map(|v| two.vertices[v as usize]);
        let (lo, hi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
        assert!(lo.x <= 0.6 && 0.6 <= hi.x, "face {f}: {t:?}");
    }
}

#[test]
fn a_vertex_pushed_through_the_opposite_side_is_found() {
    let mut ball = sphere(Vec3::ZERO, 1.0, 12, 24);
    ball.vertices[0] = Vec3::new(0.0, 0.0, -1.3);
    let crossing = found(&ball);
    // The north pole's fan, now a spike through the south cap, and the faces it pierces.
    let fan: Vec<u32> = (0..ball.triangles.len() as u32)
        .filter(|&f| ball.triangles[f as usize].contains(&0))
        .collect();
    assert!(fan.iter().all(|f| crossing.contains(f)), "{crossing:?}");
    assert!(crossing.len() > fan.len());
}

#[test]
fn faces_that_touch_without_crossing_are_not_found() {
    let cases: [(&str, [[f32; 9]; 2]); 5] = [
        // Two faces of one plane meeting at a corner only (a bowtie), given as separate
        // vertices at the same place.
        (
            "bowtie",
            [
                [0.0, 0.0, 0.0, 1.0, -0.5, 0.0, 1.0, 0.5, 0.0],
                [0.0, 0.0, 0.0, -1.0, 0.5, 0.0, -1.0, -0.5, 0.0],
            ],
        ),
        // Two faces at a corner, one leaning over the other without reaching it.
        (
            "leaning",
            [
                [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 1.0, 1.0, 1e-6, -1.0, 1.0, 1.0],
            ],
        ),
        // An edge shared by two faces folded almost flat onto each other, but not quite.
        (
            "nearly folded",
            [
                [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.5, 1.0, 0.0],
                [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1e-7],
            ],
        ),
        // A face one f32 step above another's corner, the rest far.
        (
            "one step apart",
            [
                [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                [
                    0.25,
                    0.25,
                    f32::from_bits(1),
                    2.0,
                    0.25,
                    1.0,
                    0.25,
                    2.0,
                    1.0,
                ],
            ],
        ),
        // Coplanar neighbours across an edge (a flat pair).
        (
            "flat pair",
            [
                [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                [1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0],
            ],
        ),
    ];
    for (name, faces) in cases {
        assert!(found(&soup(&faces)).is_empty(), "{name}");
    }
}

#[test]
fn faces_that_touch_beyond_their_shared_corners_are_found() {
    let cases: [(&str, [[f32; 9]; 2]); 4] = [
        // A corner of one face exactly on the inside of another.
        (
            "corner on a face",
            [
                [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                [0.25, 0.25, 0.0, 2.0, 0.25, 1.0, 0.25, 2.0, 1.0],
            ],
        ),
        // A shared edge folded over: coplanar, both faces on the same side.
        (
            "folded edge",
            [
                [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.5, 1.0, 0.0],
                [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.3, 0.5, 0.0],
            ],
        ),
        // A shared corner, the faces coplanar and overlapping along a ray from it.
        (
            "corner and a ray",
            [
                [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, -1.0, 0.0],
            ],
        ),
        // A shared corner, one face piercing the other.
        (
            "corner and a spike",
            [
                [0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.0, 0.0],
                [0.0, 0.0, 0.0, 0.5, 0.5, 1.0, 0.5, 0.5, -1.0],
            ],
        ),
    ];
    for (name, faces) in cases {
        assert_eq!(found(&soup(&faces)), [0, 1], "{name}");
    }
    // The same with shared vertex indices rather than equal positions.
    let folded = TriMesh {
        vertices: vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(0.5, 1.0, 0.0),
            Vec3::new(0.3, 0.5, 0.0),
        ],
        normals: Vec::new(),
        triangles: vec![[0, 1, 2], [1, 0, 3]],
    };
    assert_eq!(found(&folded), [0, 1]);
}

#[test]
fn adjacent_faces_of_a_flat_grid_do_not_cross_and_degenerate_faces_are_skipped() {
    let n = 20u32;
    let mut grid = TriMesh::default();
    for y in 0..=n {
        for x in 0..=n {
            grid.vertices.push(Vec3::new(x as f32, y as f32, 0.0) * 0.1);
        }
    }
    let at = |x: u32, y: u32| y * (n + 1) + x;
    for y in 0..n {
        for x in 0..n {
            let (a, b, c, d) = (at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1));
            grid.triangles.extend([[a, b, c], [a, c, d]]);
        }
    }
    assert!(found(&grid).is_empty());
    // A face repeating a vertex and a collinear one, lying on the grid's faces.
    grid.triangles.push([0, 1, 1]);
    grid.triangles.push([at(0, 0), at(1, 1), at(2, 2)]);
    assert!(found(&grid).is_empty());
}

/// A noisy double sphere: many crossings, through flat and non-flat stars.
fn tangled() -> TriMesh {
    let mut two = merged(
        &sphere(Vec3::ZERO, 1.0, 32, 64),
        &sphere(Vec3::new(0.9, 0.3, 0.0), 0.8, 32, 64),
    );
    let mut next = uniform(7);
    for p in &mut two.vertices {
        *p += 0.03 * (Vec3::new(next(), next(), next()) - 0.5);
    }
    two
}

#[test]
fn the_faces_found_do_not_depend_on_the_thread_count() {
    let two = tangled();
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    let one = pool(1).install(|| found(&two));
    assert!(one.len() > 100, "{}", one.len());
    assert_eq!(one, pool(2).install(|| found(&two)));
    assert_eq!(one, pool(3).install(|| found(&two)));
}

#[test]
fn the_grid_finds_what_testing_every_pair_finds() {
    // Small faces scattered in a box, a few large ones across it, and pairs sharing
    // vertices, in one soup; every pair tested directly for reference.
    let mut next = uniform(11);
    let mut mesh = tangled();
    mesh.triangles.truncate(400);
    for k in 0..300 {
        let size = if k % 50 == 0 { 1.5 } else { 0.08 };
        let o = Vec3::new(next(), next(), next()) * 1.5 - 0.75;
        let base = mesh.vertices.len() as u32;
        for _ in 0..3 {
            mesh.vertices
                .push(o + size * (Vec3::new(next(), next(), next()) - 0.5));
        }
        let shared = if k % 7 == 0 { 5 * k } else { base };
        mesh.triangles.push([shared, base + 1, base + 2]);
    }
    let faces = |f: usize| {
        let t = &mesh.triangles[f];
        Turns::of(&mesh.vertices, t)
            .area()
            .then(|| corners(&mesh.vertices, t))
    };
    let mut expected = vec![false; mesh.triangles.len()];
    for f in 0..mesh.triangles.len() {
        for g in f + 1..mesh.triangles.len() {
            if let (Some(p), Some(q)) = (faces(f), faces(g))
                && faces_meet(p, q)
            {
                expected[f] = true;
                expected[g] = true;
            }
        }
    }
    let expected: Vec<u32> = (0..expected.len() as u32)
        .filter(|&f| expected[f as usize])
        .collect();
    assert!(expected.len() > 50, "{}", expected.len());
    assert_eq!(found(&mesh), expected);
}
