//! The three engines (narrow band, full gather, scatter) give the same mesh, and the full-grid
//! engines refuse grids above the memory limit.

use glam::Vec3;

use crate::Engine;
use crate::config::Params;
use crate::tests::common::{fixture, lattice_ball, offsets, params, reconstruct, same_mesh};

const R: f32 = 0.01;

fn assert_engines_agree(ps: &[Vec3], r: f32, cell: &str, what: &str) {
    let p = params(r, cell);
    let band = reconstruct(ps, &p, Engine::NarrowBand).unwrap();
    let full = reconstruct(ps, &p, Engine::FullGather).unwrap();
    let scatter = reconstruct(ps, &p, Engine::Scatter).unwrap();
    assert!(band.stats.triangles > 0, "{what}: empty mesh");
    assert_eq!(
        band.mesh.triangles.len(),
        full.mesh.triangles.len(),
        "{what}"
    );
    same_mesh(&band.mesh, &full.mesh, 0.0).unwrap_or_else(|e| panic!("{what}, full gather: {e}"));
    // Where the fluid lies against a wall of the simulation box, the surface runs almost along
    // grid edges and the field changes little along them: there a last-bit difference of the
    // field moves a vertex by up to ~2e-3 cells (measured on frame_0040: 70 of 25k vertices
    // beyond 1e-4 cells, all on the walls). Hence 1e-2 cells for every vertex, 1e-4 cells for
    // 99% of them, and the same topology.
    same_mesh(&band.mesh, &scatter.mesh, 1e-2 * p.cell)
        .unwrap_or_else(|e| panic!("{what}, scatter: {e}"));
    let off = offsets(&band.mesh, &scatter.mesh, p.cell);
    let far = off.iter().filter(|&&o| o > 1e-4).count();
    assert!(
        far * 100 <= off.len(),
        "{what}, scatter: {far} of {} vertices are more than 1e-4 cells off",
        off.len()
    );
    assert_eq!(band.stats.grid, full.stats.grid, "{what}");
    assert_eq!(band.stats.grid, scatter.stats.grid, "{what}");
}

#[test]
fn three_engines_agree_on_a_ball_with_splashes() {
    let mut ps = lattice_ball(Vec3::new(0.3, -0.2, 0.1), 6.0 * R, R);
    ps.push(Vec3::new(0.3 + 9.5 * R, -0.2, 0.1));
    ps.extend(lattice_ball(
        Vec3::new(0.3, -0.2 + 11.0 * R, 0.1),
        1.5 * R,
        R,
    ));
    for cell in ["r", "r/2"] {
        assert_engines_agree(&ps, R, cell, &format!("ball at cell {cell}"));
    }
}

#[test]
fn three_engines_agree_on_a_real_frame() {
    let ps = crate::io::read_particles(&fixture("frame_0040.ply"), None)
        .unwrap()
        .positions;
    assert_engines_agree(&ps, 0.014, "r", "frame_0040 at cell r");
}

#[test]
fn full_grid_engines_refuse_above_the_memory_limit() {
    let ball = lattice_ball(Vec3::ZERO, 8.0 * R, R);
    let p = Params {
        max_memory: 100 << 10,
        ..params(R, "r/2")
    };
    for engine in [Engine::FullGather, Engine::Scatter] {
        let e = match reconstruct(&ball, &p, engine) {
            Ok(_) => panic!("{engine:?} ran above the limit"),
            Err(e) => format!("{e:#}"),
        };
        assert!(e.contains("--max-memory") && e.contains("MB"), "{e}");
    }
    // The narrow band's memory follows the surface: it fits where the full grid does not,
    // and is refused, as an error, below its own estimate.
    let roomy = Params {
        max_memory: 4 << 20,
        ..p.clone()
    };
    assert!(reconstruct(&ball, &roomy, Engine::NarrowBand).is_ok());
    for engine in [Engine::FullGather, Engine::Scatter] {
        assert!(
            reconstruct(
                &ball,
                &Params {
                    max_memory: 1 << 20,
                    ..p.clone()
                },
                engine
            )
            .is_err()
        );
    }
    for engine in [Engine::NarrowBand, Engine::Slices] {
        match reconstruct(&ball, &p, engine) {
            Err(crate::Error::Limit(e)) => assert!(e.contains("--max-memory"), "{e}"),
            other => panic!("{engine:?} under 100 KiB: {:?}", other.map(|_| ())),
        }
    }
}

#[test]
fn every_engine_ends_on_a_cell_far_beyond_the_limit() {
    // Config::validate refuses such cells; the engines must still end on them (the gathers
    // once looped over i32's whole range of lookup cells at cell 1e30, for ever).
    let ball = lattice_ball(Vec3::ZERO, 4.0 * R, R);
    for cell in ["1e30", "1000r"] {
        for engine in Engine::ALL {
            let result = reconstruct(&ball, &params(R, cell), engine);
            assert!(
                result.is_ok(),
                "{engine:?} at cell {cell}: {:?}",
                result.err()
            );
        }
    }
}
