//! The figures of one isosurface, in the shape of the paper's Tables I–V: stage times, seed and
//! used cells, the slice cache's hit ratio and the sizes of the correction steps.

use std::fmt;
use std::time::Duration;

use serde::Serialize;

/// Upper ends of the bins of [`CorrectionStats::histogram`], as fractions of the edge.
pub const CORRECTION_BINS: [f64; 6] = [0.001, 0.01, 0.05, 0.1, 0.2, 1.0];

/// How far the correction moved the vertices from Marching Cubes' linear estimate (Table V).
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct CorrectionStats {
    /// Vertices corrected.
    pub vertices: usize,
    /// Mean, largest and standard deviation of the move, in world units.
    pub mean: f64,
    /// See `mean`.
    pub max: f64,
    /// See `mean`.
    pub std_dev: f64,
    /// Mean move as a fraction of the cube edge.
    pub mean_fraction: f64,
    /// Moves per bin of [`CORRECTION_BINS`] (fractions of the edge).
    pub histogram: [usize; 6],
}

impl CorrectionStats {
    /// From the moves as fractions of an edge of `edge` world units.
    pub fn of(fractions: impl Iterator<Item = f32>, edge: f32) -> CorrectionStats {
        let mut s = CorrectionStats::default();
        let (mut sum, mut sum2, mut max) = (0.0f64, 0.0f64, 0.0f64);
        for f in fractions {
            let f = f64::from(f);
            s.vertices += 1;
            sum += f;
            sum2 += f * f;
            max = max.max(f);
            let bin = CORRECTION_BINS.iter().position(|&b| f < b).unwrap_or(5);
            s.histogram[bin] += 1;
        }
        if s.vertices > 0 {
            let n = s.vertices as f64;
            let edge = f64::from(edge);
            s.mean_fraction = sum / n;
            s.mean = s.mean_fraction * edge;
            s.max = max * edge;
            s.std_dev = (sum2 / n - (sum / n).powi(2)).max(0.0).sqrt() * edge;
        }
        s
    }
}

/// Stage wall times.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct IsoTimings {
    /// Sorting the particles, their volumes and derived values ("grid construction").
    pub grid_construction: Duration,
    /// Seed cell selection.
    pub seed_cells: Duration,
    /// Surface following and triangulation.
    pub surface_extraction: Duration,
    /// Placing the vertices: linear estimate and correction steps.
    pub correction: Duration,
    /// Trimming, normals and extra attributes.
    pub finishing: Duration,
}

/// Counts of one isosurface.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct IsoStats {
    /// The level.
    pub level: f64,
    /// Virtual cell edge, world units.
    pub cell: f32,
    /// Mean number of other particles whose (scaled) kernel reaches a particle, over a fixed
    /// sample of them (Sec. IV-D: about 70 in the paper's dam break at scale 1).
    pub support_neighbours: f64,
    /// Cells of the particles' bounding box in the virtual grid (never materialised).
    pub virtual_cells: u64,
    /// Seed cells (Sec. III-C).
    pub seed_cells: usize,
    /// Cells materialised: seeds and cells the queue reached.
    pub visited_cells: usize,
    /// Cells the isosurface crosses (triangulated).
    pub crossed_cells: usize,
    /// Cells dropped for a corner below the node threshold.
    pub discarded_cells: usize,
    /// Node values asked of the slice cache, and evaluated because it had not got them.
    pub node_lookups: u64,
    /// See `node_lookups`.
    pub node_evaluations: u64,
    /// 1 − evaluations / lookups.
    pub cache_hit_ratio: f64,
    /// Most nodes the cache held at once.
    pub cache_peak_nodes: usize,
    /// Triangles before trimming, and of trimming cases a–e (Fig. 3).
    pub untrimmed_triangles: usize,
    /// See `untrimmed_triangles`.
    pub trim_cases: [usize; 5],
    /// Vertices and triangles of the mesh.
    pub vertices: usize,
    /// See `vertices`.
    pub triangles: usize,
    /// The correction steps' sizes.
    pub correction: CorrectionStats,
    /// Stage times.
    pub timings: IsoTimings,
}

impl IsoStats {
    /// The stages together, without the grid construction (a preprocessing step, Table II).
    pub fn total(&self) -> Duration {
        let t = &self.timings;
        t.seed_cells + t.surface_extraction + t.correction + t.finishing
    }
}

impl fmt::Display for IsoStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        let (t, c) = (&self.timings, &self.correction);
        write!(
            f,
            "level {}: {} triangles, {} vertices; {:.1} neighbours in a support; virtual cells {}, seeds {}, visited {}, crossed \
             {}, discarded {}; cache hit ratio {:.3} ({} of {} node lookups evaluated, ≤ {} \
             nodes held); trimming a–e {:?}; correction mean {:.3e} max {:.3e} sd {:.3e} \
             ({:.2} % of the edge), bins {:?}; grid {:.0} ms, seeds {:.0} ms, extraction {:.0} \
             ms, correction {:.0} ms, trimming+normals {:.0} ms",
            self.level,
            self.triangles,
            self.vertices,
            self.support_neighbours,
            self.virtual_cells,
            self.seed_cells,
            self.visited_cells,
            self.crossed_cells,
            self.discarded_cells,
            self.cache_hit_ratio,
            self.node_evaluations,
            self.node_lookups,
            self.cache_peak_nodes,
            self.trim_cases,
            c.mean,
            c.max,
            c.std_dev,
            100.0 * c.mean_fraction,
            c.histogram,
            ms(t.grid_construction),
            ms(t.seed_cells),
            ms(t.surface_extraction),
            ms(t.correction),
            ms(t.finishing),
        )
    }
}
