//! Memory figures of the counting allocator. One test only: the allocator counts the whole
//! process, and this test binary runs nothing else meanwhile.

mod common;

use common::{fixture, params};
use splash::recon::full_grid::{Grid, needed_bytes};
use splash::recon::{Engine, reconstruct};

#[test]
fn memory_follows_the_cell_and_the_narrow_band_needs_least() {
    assert!(splash::memory::counting(), "the counting allocator is off");
    let ps = splash::io::read_particles(&fixture("frame_0040.ply"), None).unwrap();
    let heap = |cell: &str, engine| {
        let s = reconstruct(&ps, &params(0.014, cell), engine)
            .unwrap()
            .stats;
        // Every stage that ran holds something; the peak is the largest stage's.
        assert!(s.stage_heap.scalar_field > 0 && s.stage_heap.triangulation > 0);
        assert_eq!(s.heap_peak, s.stage_heap.max());
        assert!(s.peak_rss as usize > s.heap_peak);
        s.heap_peak
    };
    let mut at_half = Vec::new();
    for engine in Engine::ALL {
        let (r, r2) = (heap("r", engine), heap("r/2", engine));
        assert!(r2 > 2 * r, "{engine:?}: {r} bytes at r, {r2} at r/2");
        at_half.push(r2);
    }
    let [band, gather, scatter] = at_half[..] else {
        unreachable!()
    };
    assert!(
        band < gather && gather < scatter,
        "{band} {gather} {scatter}"
    );
    // The estimate that --max-memory checks covers the grid; the mesh comes on top.
    let p = params(0.014, "r/2");
    let grid = Grid::around(&ps, p.cell, p.support).unwrap();
    for (engine, measured) in [(Engine::FullGather, gather), (Engine::Scatter, scatter)] {
        let need = needed_bytes(engine, &grid, ps.len()).unwrap() as f64;
        let ratio = measured as f64 / need;
        assert!(
            (0.9..1.6).contains(&ratio),
            "{engine:?}: measured/estimate {ratio}"
        );
    }
}
