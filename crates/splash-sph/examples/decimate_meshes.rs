//! Decimates splash's binary PLY meshes and reports what the decimation kept: faces before and
//! after, closedness, components and Euler characteristic, volume change, time, and the largest
//! distance of a vertex to the undecimated surface, measured exactly and independently of the
//! decimation's own check (a uniform grid of triangle boxes, projection or edge distances).
//!
//! `cargo run --release --example decimate_meshes -- SPACING FACTOR MESH.ply...`
//! (the error allowed is FACTOR × SPACING; `--no-distance` skips the distance measurement).
//! `--clip=X0,Y0,Z0,X1,Y1,Z1` and `--min-component=V` (in SPACING³) also clip each mesh to the
//! box and drop its small components, and report the results' topology and volume.

use splash_sph::mesh::{
    clip_to_box, component_volumes, decimate, drop_small_components, signed_volume, topology,
};
use splash_sph::{TriMesh, Vec3};
use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read};
use std::time::Instant;

/// Reads the binary little-endian PLY that splash writes (float x y z [nx ny nz], then
/// uchar-int faces): enough for these measurements, not a general reader.
fn read_splash_ply(path: &str) -> TriMesh {
    let mut input = BufReader::new(std::fs::File::open(path).expect(path));
    let (mut vertices, mut faces, mut floats) = (0usize, 0usize, 0usize);
    loop {
        let mut line = String::new();
        input.read_line(&mut line).unwrap();
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["element", "vertex", n] => vertices = n.parse().unwrap(),
            ["element", "face", n] => faces = n.parse().unwrap(),
            ["property", "float", _] => floats += 1,
            ["end_header"] => break,
            _ => {}
        }
    }
    let mut bytes = vec![0u8; vertices * floats * 4];
    input.read_exact(&mut bytes).unwrap();
    let f = |i: usize| f32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
    let mut mesh = TriMesh::default();
    for v in 0..vertices {
        let base = v * floats;
        mesh.vertices
            .push(Vec3::new(f(base), f(base + 1), f(base + 2)));
        if floats == 6 {
            mesh.normals
                .push(Vec3::new(f(base + 3), f(base + 4), f(base + 5)));
        }
    }
    let mut face = [0u8; 13];
    for _ in 0..faces {
        input.read_exact(&mut face).unwrap();
        assert_eq!(face[0], 3, "{path}: not a triangle");
        let i = |k: usize| u32::from_le_bytes(face[1 + 4 * k..5 + 4 * k].try_into().unwrap());
        mesh.triangles.push([i(0), i(1), i(2)]);
    }
    mesh
}

/// Distance from `p` to the triangle `t`: the projection when it falls inside, else the
/// nearest edge.
fn distance(p: Vec3, t: [Vec3; 3]) -> f64 {
    let (p, t) = (p.as_dvec3(), t.map(|v| v.as_dvec3()));
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    if n.length() > 0.0 {
        let n = n.normalize();
        let q = p - n * n.dot(p - t[0]);
        if (0..3).all(|i| (t[(i + 1) % 3] - t[i]).cross(q - t[i]).dot(n) >= 0.0) {
            return (p - q).length();
        }
    }
    (0..3)
        .map(|i| {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            let s = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            (p - (a + s * (b - a))).length()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The largest distance of `points` to `original`, searched within `radius` (infinity when
/// some point has no triangle that close).
fn largest_distance(points: &[Vec3], original: &TriMesh, radius: f32) -> f64 {
    let cell = radius.max(1e-9);
    let key = |p: Vec3| (p / cell).floor().as_ivec3().to_array();
    let mut grid: HashMap<[i32; 3], Vec<u32>> = HashMap::new();
    for (i, t) in original.triangles.iter().enumerate() {
        let p = t.map(|v| original.vertices[v as usize]);
        let (lo, hi) = (key(p[0].min(p[1]).min(p[2])), key(p[0].max(p[1]).max(p[2])));
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    grid.entry([x, y, z]).or_default().push(i as u32);
                }
            }
        }
    }
    let mut worst = 0.0f64;
    for &p in points {
        let (lo, hi) = (key(p - radius), key(p + radius));
        let mut best = f64::INFINITY;
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    for &t in grid.get(&[x, y, z]).into_iter().flatten() {
                        let tri =
                            original.triangles[t as usize].map(|v| original.vertices[v as usize]);
                        best = best.min(distance(p, tri));
                    }
                }
            }
        }
        worst = worst.max(best);
    }
    worst
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let measure_distance = !args.iter().any(|a| a == "--no-distance");
    let option = |name: &str| {
        args.iter()
            .find_map(|a| a.strip_prefix(name).map(str::to_string))
    };
    let clip = option("--clip=").map(|text| {
        let v: Vec<f32> = text.split(',').map(|x| x.trim().parse().unwrap()).collect();
        <[f32; 6]>::try_from(v).expect("--clip= takes six numbers")
    });
    let min_component: Option<f64> = option("--min-component=").map(|v| v.parse().unwrap());
    let args: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    let spacing: f32 = args[0].parse().unwrap();
    let factor: f32 = args[1].parse().unwrap();
    let max_error = factor * spacing;
    let (mut before_sum, mut after_sum, mut count) = (0usize, 0usize, 0usize);
    println!(
        "mesh faces_before faces_after closed_manifold components euler volume_change_% seconds max_vertex_distance/r max_centroid_distance/r"
    );
    for path in &args[2..] {
        let mesh = read_splash_ply(path);
        let start = Instant::now();
        let out = decimate(&mesh, max_error).unwrap();
        let seconds = start.elapsed().as_secs_f64();
        let (t0, t1) = (topology(&mesh), topology(&out));
        let (v0, v1) = (signed_volume(&mesh), signed_volume(&out));
        let components = (
            component_volumes(&mesh).len(),
            component_volumes(&out).len(),
        );
        let (worst, worst_centroid) = if measure_distance {
            let centroids: Vec<Vec3> = out
                .triangles
                .iter()
                .map(|t| t.iter().map(|&v| out.vertices[v as usize]).sum::<Vec3>() / 3.0)
                .collect();
            (
                largest_distance(&out.vertices, &mesh, 2.0 * max_error) / f64::from(spacing),
                largest_distance(&centroids, &mesh, 20.0 * max_error) / f64::from(spacing),
            )
        } else {
            (f64::NAN, f64::NAN)
        };
        println!(
            "{} {} {} {} {}->{} {}->{} {:+.4} {seconds:.3} {worst:.6} {worst_centroid:.4}",
            std::path::Path::new(path)
                .file_name()
                .unwrap()
                .to_string_lossy(),
            mesh.triangles.len(),
            out.triangles.len(),
            t0.is_closed_manifold() && t1.is_closed_manifold(),
            components.0,
            components.1,
            t0.euler_characteristic,
            t1.euler_characteristic,
            100.0 * (v1 / v0 - 1.0),
        );
        if let Some(aabb) = clip {
            let start = Instant::now();
            let clipped = clip_to_box(&mesh, aabb).unwrap();
            let t = topology(&clipped);
            println!(
                "  clipped: {} faces, closed manifold {}, components {}, volume {:.6} of {:.6}, {:.3} s",
                clipped.triangles.len(),
                t.is_closed_manifold(),
                t.components,
                signed_volume(&clipped),
                v0,
                start.elapsed().as_secs_f64()
            );
        }
        if let Some(v) = min_component {
            let (kept, dropped) =
                drop_small_components(&mesh, v * f64::from(spacing).powi(3)).unwrap();
            println!(
                "  components below {v} r³: {dropped} dropped, {} left, closed manifold {}",
                component_volumes(&kept).len(),
                topology(&kept).is_closed_manifold()
            );
        }
        before_sum += mesh.triangles.len();
        after_sum += out.triangles.len();
        count += 1;
    }
    println!(
        "mean faces: {} -> {}",
        before_sum / count.max(1),
        after_sum / count.max(1)
    );
}
