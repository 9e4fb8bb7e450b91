//! `correct = N` (Marching Correctors, Sec. III-D2): every vertex ends far closer to the field's
//! isosurface than linear interpolation puts it, as the field evaluated at the vertex on its
//! own says; it stays on its cube edge; the triangles, the engines' agreement and the
//! independence of the thread count stay as they were.

use crate::Engine;
use crate::config::Params;
use crate::mesh::TriMesh;
use crate::mesh::topology::topology;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::Neighbourhood;
use crate::recon::stages::vertex_correction::edge_of;
use crate::report::CorrectionFigures;
use crate::tests::common::{Jitter, field_params, fixture, lattice_ball, reconstruct, same_mesh};
use glam::Vec3;

fn corrected(p: &Params, n: u32) -> Params {
    Params {
        correct: n,
        ..p.clone()
    }
}

/// |f − iso| at each vertex, from the particles gathered around that vertex alone (not the
/// correction's gather by cell), with the field fitted to the frame where it adapts.
fn residuals(ps: &[Vec3], p: &Params, mesh: &TriMesh) -> Vec<f32> {
    let mut handlers = HandlerArray::new(ps, 2.0 * p.spacing).unwrap();
    handlers.channels = p.field.particle_channels(&handlers);
    let fitted = p.field.fit(&handlers).transpose().unwrap();
    let (field, handlers) = match &fitted {
        Some(f) => (f.field.as_ref(), &f.handlers),
        None => (p.field.as_ref(), &handlers),
    };
    let mut near = Neighbourhood::default();
    mesh.vertices
        .iter()
        .map(|&v| {
            near.gather_box(handlers, v, v, field.support(), field.reach_channel());
            field.value(&near, Vec3::ZERO).abs()
        })
        .collect()
}

/// Largest, 99th percentile and mean.
fn figures(r: &[f32]) -> Residuals {
    let mut sorted = r.to_vec();
    sorted.sort_unstable_by(f32::total_cmp);
    Residuals {
        max: sorted[sorted.len() - 1],
        p99: sorted[sorted.len() * 99 / 100],
        mean: r.iter().map(|&x| f64::from(x)).sum::<f64>() / r.len() as f64,
    }
}

#[derive(Debug)]
struct Residuals {
    max: f32,
    p99: f32,
    mean: f64,
}

/// The corrected residuals against the plain ones: the largest no larger, the 99th
/// percentile `p99` times smaller, the mean `mean` times.
fn assert_closer(before: &Residuals, after: &Residuals, p99: f32, mean: f64, what: &str) {
    let why = || format!("{what}: {before:?} → {after:?}");
    assert!(after.max <= before.max * 1.001, "{}", why());
    assert!(after.p99 * p99 < before.p99, "{}", why());
    assert!(after.mean * mean < before.mean, "{}", why());
}

/// The corrected mesh has the plain mesh's triangles, and each vertex the plain one's edge;
/// returns the residuals before and after, and the correction's figures.
fn check_correction(
    ps: &[Vec3],
    p: &Params,
    engine: Engine,
    what: &str,
) -> (Residuals, Residuals, CorrectionFigures) {
    let plain = reconstruct(ps, p, engine).unwrap();
    let fixed = reconstruct(ps, &corrected(p, 3), engine).unwrap();
    let (a, b) = (&plain.mesh, &fixed.mesh);
    assert!(!a.is_empty(), "{what}");
    assert_eq!(a.triangles, b.triangles, "{what}: triangles changed");
    assert_eq!(a.vertices.len(), b.vertices.len(), "{what}");
    assert_eq!(plain.stats.correction, CorrectionFigures::default());
    for (u, v) in a.vertices.iter().zip(&b.vertices) {
        if let Some(edge) = edge_of(*u, p.cell) {
            let changed = (0..3).filter(|&k| u[k] != v[k]).count();
            assert!(changed <= 1, "{what}: {u} moved to {v}, off its edge");
            // On the same edge, or at its end.
            if let Some(e) = edge_of(*v, p.cell) {
                assert_eq!(e, edge, "{what}: {u} moved to {v}");
            }
            assert!((*v - *u).length() <= p.cell, "{what}: {u} moved to {v}");
        } else {
            assert_eq!(u, v, "{what}: a vertex on a grid corner moved");
        }
    }
    let (ta, tb) = (topology(a), topology(b));
    assert_eq!(
        (ta.components, ta.euler_characteristic),
        (tb.components, tb.euler_characteristic),
        "{what}"
    );
    let (before, after) = (residuals(ps, p, a), residuals(ps, p, b));
    // Rounding: the test gathers other particles in another order.
    let slack = 1e-4 * before.iter().copied().fold(0.0, f32::max);
    for (i, (x, y)) in before.iter().zip(&after).enumerate() {
        assert!(
            *y <= x * 1.001 + slack,
            "{what}: vertex {i}: |f − iso| {x} → {y}"
        );
    }
    (figures(&before), figures(&after), fixed.stats.correction)
}

#[test]
fn every_field_lands_its_vertices_on_its_isosurface() {
    let r = 0.01;
    let mut jitter = Jitter::new(3);
    let ps: Vec<Vec3> = lattice_ball(Vec3::ZERO, 5.0 * r, r)
        .into_iter()
        .map(|p| p + jitter.vec3() * 0.4 * r)
        .collect();
    for field in crate::field::FieldConfig::KINDS {
        for cell in ["r", "r/2"] {
            let what = format!("{field} at {cell}");
            let p = field_params(field, r, cell);
            let (before, after, figures) = check_correction(&ps, &p, Engine::NarrowBand, &what);
            eprintln!("{what}: before {before:?}, after {after:?}; {figures:?}");
            assert!(figures.moved > figures.vertices / 2, "{what}: {figures:?}");
            assert_closer(&before, &after, 5.0, 20.0, &what);
        }
    }
}

/// The engines correct the same vertices the same way, and no engine's mesh depends on the
/// thread count.
#[test]
fn engines_and_thread_counts_agree_on_the_corrected_mesh() {
    let r = 0.014;
    let ps = crate::io::read_particles(&fixture("frame_0040.ply"), None)
        .unwrap()
        .positions;
    for field in ["ssp07", "density"] {
        let p = corrected(&field_params(field, r, "r"), 3);
        let run = |engine, threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| reconstruct(&ps, &p, engine).unwrap().mesh)
        };
        let band = run(Engine::NarrowBand, 2);
        assert_eq!(band, run(Engine::NarrowBand, 1), "{field}: narrow band");
        let slices = run(Engine::Slices, 2);
        assert_eq!(slices, run(Engine::Slices, 1), "{field}: slices");
        same_mesh(&band, &slices, 1e-2 * p.cell).unwrap_or_else(|e| panic!("{field}: {e}"));
        let full = run(Engine::FullGather, 2);
        same_mesh(&band, &full, 1e-2 * p.cell).unwrap_or_else(|e| panic!("{field}: {e}"));
    }
}

/// On a real frame the vertices land on the surface: the 99th percentile of |f − iso| drops
/// at least tenfold, the mean fiftyfold, and no vertex's grows.
#[test]
fn a_real_frame_lands_on_its_isosurface() {
    let r = 0.014;
    let ps = crate::io::read_particles(&fixture("frame_0040.ply"), None)
        .unwrap()
        .positions;
    for field in ["ssp07", "density"] {
        for cell in ["r", "r/2"] {
            let what = format!("frame_0040, {field} at {cell}");
            let p = field_params(field, r, cell);
            let (before, after, figures) = check_correction(&ps, &p, Engine::NarrowBand, &what);
            eprintln!("{what}: before {before:?}, after {after:?}; {figures:?}");
            assert_closer(&before, &after, 10.0, 50.0, &what);
        }
    }
}
