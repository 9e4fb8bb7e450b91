//! The baselines of Fig. 7 of Rosenberg & Birdwell 2008 (surface-following Marching Cubes in
//! blocks with 3D arrays, and with hash maps) give the slices engine's mesh to the bit: the
//! same vertices in the same order, normals, and triangles, in any thread count.

use super::slices::sorted;
use crate::config::Baseline;
use crate::config::{Normals, Params};
use crate::recon::Reconstruction;
use crate::tests::common::{field_params, fixture, shared_data};
use crate::{Engine, Vec3};

fn run(ps: &[Vec3], p: &Params, baseline: Option<Baseline>, threads: usize) -> Reconstruction {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let p = Params {
        engine: Engine::Slices,
        baseline,
        ..p.clone()
    };
    pool.install(|| crate::recon::reconstruct(ps, &p, None).unwrap())
}

/// Every baseline against the slices engine on `ps` with `field` at each cell.
fn assert_same_as_slices(name: &str, ps: &[Vec3], field: &str, cells: &[&str], normals: Normals) {
    for &cell in cells {
        let p = Params {
            normals,
            ..field_params(field, 0.014, cell)
        };
        let slices = run(ps, &p, None, 2);
        assert!(slices.mesh.triangles.len() > 1000, "{name}");
        for (baseline, threads) in [
            (Baseline::BlockedCubes, 1),
            (Baseline::BlockedCubes, 2),
            (Baseline::HashedCubes, 1),
        ] {
            let what = format!("{name}, {field} at {cell}, {baseline:?}, {threads} threads");
            let other = run(ps, &p, Some(baseline), threads);
            let (a, b) = (&slices.mesh, &other.mesh);
            assert_eq!(a.vertices.len(), b.vertices.len(), "{what}: vertices");
            assert!(a.vertices == b.vertices, "{what}: vertex positions");
            assert!(a.normals == b.normals, "{what}: normals");
            assert!(
                sorted(&a.triangles) == sorted(&b.triangles),
                "{what}: triangles"
            );
            assert!(other.stats.surface_cells > 0, "{what}");
            let s = other.stats.slices;
            assert!(
                s.render_bytes_max > 0 && s.cache_bytes_max > 0,
                "{what}: {s:?}"
            );
        }
    }
}

fn read(path: &std::path::Path) -> Vec<Vec3> {
    crate::io::read_particles(path, None).unwrap().positions
}

#[test]
fn baselines_give_the_slices_mesh_on_the_fixture() {
    let ps = read(&fixture("frame_0040.ply"));
    assert_same_as_slices("frame_0040", &ps, "metaball", &["r", "r/2"], Normals::Field);
    assert_same_as_slices("frame_0040", &ps, "ssp07", &["r"], Normals::Grid);
}

#[test]
fn baselines_give_the_slices_mesh_on_a_real_frame() {
    let Some(path) = shared_data("cbd-small/frame_0061.ply") else {
        return;
    };
    let ps = read(&path);
    assert_same_as_slices(
        "cbd-small frame_0061",
        &ps,
        "ssp07",
        &["r", "r/2"],
        Normals::Field,
    );
}
