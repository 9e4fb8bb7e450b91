//! Per-frame figures: stage times, counts and the memory held by the reconstruction.

use std::fmt;
use std::time::{Duration, Instant};

/// Times of the stages of Algorithm 1 (Akinci et al. 2012), plus I/O.
#[derive(Debug, Clone, Copy, Default)]
pub struct Timings {
    pub read: Duration,
    /// Sorting the handler array (Sec. 4.1, "Identification of the contributing particles").
    pub handler_array: Duration,
    /// t_sp: colour field and neighbour counts.
    pub surface_particles: Duration,
    pub band: Duration,
    /// t_sf.
    pub scalar_field: Duration,
    /// t_tri.
    pub triangulation: Duration,
    pub write: Duration,
}

impl Timings {
    pub fn reconstruction(&self) -> Duration {
        self.handler_array
            + self.surface_particles
            + self.band
            + self.scalar_field
            + self.triangulation
    }
}

/// Runs `f`, adding its wall time to `slot`: one timing scope per stage.
pub fn timed<T>(slot: &mut Duration, f: impl FnOnce() -> T) -> T {
    let start = Instant::now();
    let out = f();
    *slot += start.elapsed();
    out
}

/// Counts and memory of one reconstructed frame.
#[derive(Debug, Clone, Copy, Default)]
pub struct FrameStats {
    pub particles: usize,
    pub surface_particles: usize,
    /// Bricks of 8³ vertices holding surface vertices.
    pub bricks: usize,
    pub surface_vertices: usize,
    /// Vertices added to close the band where the surface left it (included above).
    pub closure_vertices: usize,
    pub surface_cells: usize,
    pub triangles: usize,
    pub vertices: usize,
    /// Largest sum of the bytes held at once by the reconstruction's own arrays (handler array,
    /// band, field values, mesh), measured from their capacities.
    pub peak_bytes: usize,
    pub timings: Timings,
}

impl fmt::Display for FrameStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        let t = &self.timings;
        write!(
            f,
            "{} particles ({} surface), {} surface vertices, {} triangles; \
             read {:.0} ms, sort {:.0} ms, t_sp {:.0} ms, band {:.0} ms, t_sf {:.0} ms, \
             t_tri {:.0} ms, write {:.0} ms; {:.1} MB",
            self.particles,
            self.surface_particles,
            self.surface_vertices,
            self.triangles,
            ms(t.read),
            ms(t.handler_array),
            ms(t.surface_particles),
            ms(t.band),
            ms(t.scalar_field),
            ms(t.triangulation),
            ms(t.write),
            self.peak_bytes as f64 / 1e6
        )
    }
}
