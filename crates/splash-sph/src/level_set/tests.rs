//! The level set of a reconstructed ball of particles against what a signed distance must be:
//! −radius at the centre, +2 cells two cells out, the mesh's own distance at every active voxel,
//! a gradient of length one in the band, zero at the mesh's vertices (the figures printed);
//! a tree that follows the surface; and the same on one thread or two.

use glam::{IVec3, Vec3};
use rustc_hash::FxHashMap;

use super::{HALF_WIDTH_VOXELS, LevelSet};
use crate::Engine;
use crate::mesh::{SignedDistance, TriMesh};
use crate::tests::common::{lattice_ball, params, reconstruct};

const R: f32 = 0.01;

fn ball() -> (TriMesh, Vec3, f32) {
    let centre = Vec3::new(0.3, -0.2, 0.1);
    let particles = lattice_ball(centre, 8.0 * R, R);
    let mesh = reconstruct(&particles, &params(R, "r/2"), Engine::NarrowBand)
        .unwrap()
        .mesh;
    let radius = mesh
        .vertices
        .iter()
        .map(|v| v.distance(centre))
        .sum::<f32>()
        / mesh.vertices.len() as f32;
    (mesh, centre, radius)
}

/// Active voxels by index.
fn voxels(ls: &LevelSet) -> FxHashMap<IVec3, f32> {
    ls.coordinates()
        .into_iter()
        .map(IVec3::from)
        .zip(ls.values.iter().copied())
        .collect()
}

/// φ at `p` interpolated trilinearly from the eight voxels around it (all active).
fn trilinear(phi: &FxHashMap<IVec3, f32>, p: Vec3, voxel: f32) -> Option<f32> {
    let q = p / voxel;
    let base = q.floor();
    let (i, f) = (base.as_ivec3(), q - base);
    let mut sum = 0.0;
    for c in 0..8 {
        let o = IVec3::new(c >> 2, (c >> 1) & 1, c & 1);
        let w = (if o.x == 1 { f.x } else { 1.0 - f.x })
            * (if o.y == 1 { f.y } else { 1.0 - f.y })
            * (if o.z == 1 { f.z } else { 1.0 - f.z });
        sum += w * phi.get(&(i + o))?;
    }
    Some(sum)
}

#[test]
fn a_ball_has_its_distance_in_the_band() {
    let (mesh, centre, radius) = ball();
    // A voxel of 3r puts the centre (radius ≈ 7.75r) inside the band of 3 voxels.
    let voxel = 3.0 * R;
    let ls = LevelSet::of_mesh(&mesh, voxel).unwrap();
    let phi = voxels(&ls);
    let at_centre = trilinear(&phi, centre, voxel).expect("the centre is in the band");
    assert!(
        (at_centre + radius).abs() < voxel,
        "φ(centre) {at_centre}, radius {radius}"
    );
    let out = centre + Vec3::new(1.0, 1.0, -1.0).normalize() * (radius + 2.0 * voxel);
    let outside = trilinear(&phi, out, voxel).expect("two cells out is in the band");
    assert!(
        (outside - 2.0 * voxel).abs() < 0.25 * voxel,
        "φ two cells out: {outside}"
    );
}

#[test]
fn a_ball_level_set_is_the_meshs_signed_distance() {
    let (mesh, _, _) = ball();
    let voxel = R / 2.0;
    let ls = LevelSet::of_mesh(&mesh, voxel).unwrap();
    let band = HALF_WIDTH_VOXELS * voxel;
    assert_eq!(ls.half_width, band);
    let phi = voxels(&ls);
    // Every active voxel holds the mesh's signed distance, within the band; every voxel
    // within the band is active.
    let exact = SignedDistance::new(&mesh.vertices, &mesh.triangles, 2.0 * band);
    let mut worst: f32 = 0.0;
    for (v, &d) in &phi {
        let truth = exact.at(v.as_vec3() * voxel).unwrap();
        assert!(
            d.abs() < band && d.signum() == truth.signum(),
            "{v}: {d} against {truth}"
        );
        worst = worst.max((d - truth).abs());
    }
    assert!(
        worst < 0.02 * voxel,
        "worst distance error {} voxels",
        worst / voxel
    );
    println!("worst distance error {:.2e} voxels", worst / voxel);
    let (lo, hi) = phi
        .keys()
        .fold((IVec3::MAX, IVec3::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
    let mut missing = 0;
    for x in lo.x..=hi.x {
        for y in lo.y..=hi.y {
            for z in lo.z..=hi.z {
                let v = IVec3::new(x, y, z);
                let d = exact.at(v.as_vec3() * voxel);
                if d.is_some_and(|d| d.abs() < band * 0.999) && !phi.contains_key(&v) {
                    missing += 1;
                }
            }
        }
    }
    assert_eq!(missing, 0, "voxels within the band left inactive");
    // |∇φ| = 1 by central differences wherever the six neighbours are active.
    let mut gradients = Vec::new();
    for v in phi.keys() {
        let d = |step: IVec3| Some(phi.get(&(*v + step))? - phi.get(&(*v - step))?);
        if let (Some(x), Some(y), Some(z)) = (d(IVec3::X), d(IVec3::Y), d(IVec3::Z)) {
            let g = Vec3::new(x, y, z).length() / (2.0 * voxel);
            assert!((g - 1.0).abs() < 0.1, "|∇φ| {g} at {v}");
            gradients.push(g);
        }
    }
    assert!(
        gradients.len() > phi.len() / 2,
        "{} of {}",
        gradients.len(),
        phi.len()
    );
    let (low, high) = gradients
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), &g| (l.min(g), h.max(g)));
    println!(
        "|∇φ| from {low:.4} to {high:.4} at {} voxels",
        gradients.len()
    );
    // The zero crossing passes through the mesh's vertices.
    let mut off: Vec<f32> = mesh
        .vertices
        .iter()
        .map(|p| {
            trilinear(&phi, *p, voxel)
                .expect("vertices lie in the band")
                .abs()
                / voxel
        })
        .collect();
    off.sort_by(f32::total_cmp);
    let at = |q: f64| off[((off.len() - 1) as f64 * q).round() as usize];
    println!(
        "φ at the mesh's {} vertices, in voxels: median {:.4}, p99 {:.4}, max {:.4}",
        off.len(),
        at(0.5),
        at(0.99),
        at(1.0)
    );
    assert!(at(1.0) < 0.1, "φ {} voxels at a vertex", at(1.0));
    // The leaves follow the surface: about the band's volume, not the ball's.
    let shell = 4.0 * std::f32::consts::PI * (8.0 * R / voxel).powi(2) * 2.0 * HALF_WIDTH_VOXELS;
    assert!(
        (phi.len() as f32) < 1.3 * shell,
        "{} active voxels",
        phi.len()
    );
    assert!(ls.tree.leaves.len() * 512 < 4 * phi.len());
}

#[test]
fn one_thread_or_two_make_the_same_level_set() {
    let (mesh, _, _) = ball();
    let on = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| LevelSet::of_mesh(&mesh, R / 2.0).unwrap())
    };
    let (one, two) = (on(1), on(2));
    assert_eq!(one.tree, two.tree);
    let bits = |ls: &LevelSet| ls.values.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&one), bits(&two));
}

#[test]
fn bad_meshes_and_voxels_are_errors() {
    let (mut mesh, _, _) = ball();
    assert!(LevelSet::of_mesh(&mesh, 0.0).is_err());
    assert!(LevelSet::of_mesh(&mesh, f32::NAN).is_err());
    mesh.vertices[0].x = f32::INFINITY;
    assert!(
        LevelSet::of_mesh(&mesh, R)
            .unwrap_err()
            .to_string()
            .contains("vertex 0")
    );
    mesh.triangles[3][1] = mesh.vertices.len() as u32;
    assert!(
        LevelSet::of_mesh(&mesh, R)
            .unwrap_err()
            .to_string()
            .contains("triangle 3")
    );
}
