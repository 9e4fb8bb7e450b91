//! The report of one reconstruction: counts, the reconstruction's own array bytes, and (when
//! the caller passes an [`Observer`]) the time and heap of each stage of Algorithm 1
//! ([`FrameStats`]); and the report of a run over frames, one [`FrameRecord`] per frame with
//! their average, the machine and the build, as JSON, CSV or Markdown ([`Report`], what
//! `splash recon --report` writes).

mod records;

use std::fmt;
use std::time::{Duration, Instant};

use serde::Serialize;

pub use records::{Build, Figures, FrameRecord, Machine, Report, ReportFormat, cell_label};

/// Times of the stages of Algorithm 1 (Akinci et al. 2012), plus I/O.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Timings {
    /// Reading the particle file (set by callers that read it).
    pub read: Duration,
    /// Sorting the handler array (Sec. 4.1, "Identification of the contributing particles").
    pub handler_array: Duration,
    /// t_sp: colour field and neighbour counts.
    pub surface_particles: Duration,
    /// The band of surface vertices (Sec. 4.1), and its closure.
    pub band: Duration,
    /// t_sf.
    pub scalar_field: Duration,
    /// t_tri.
    pub triangulation: Duration,
    /// Post-processing the mesh (smoothing, volume; issue 25).
    pub post: Duration,
    /// Writing the mesh (set by callers that write it); for VDB output, making its level set
    /// too.
    pub write: Duration,
}

impl Timings {
    /// The stages of the reconstruction together, without I/O.
    pub fn reconstruction(&self) -> Duration {
        self.handler_array
            + self.surface_particles
            + self.band
            + self.scalar_field
            + self.triangulation
            + self.post
    }
}

/// A stage of Algorithm 1, for its time and peak heap.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Sorting the particles into the handler array.
    HandlerArray,
    /// The surface particles (colour field and neighbour counts), t_sp.
    SurfaceParticles,
    /// The band of surface vertices.
    Band,
    /// The scalar field on the band, t_sf.
    ScalarField,
    /// The triangles and their normals, t_tri.
    Triangulation,
    /// Post-processing the mesh (smoothing, volume).
    Post,
}

/// What an [`Observer`] measured of one run of a stage.
#[derive(Debug, Clone, Copy, Default)]
pub struct StageFigures {
    /// Wall time.
    pub time: Duration,
    /// Peak heap bytes during the stage above the heap held when the reconstruction started.
    pub heap_peak: usize,
}

/// Measures the stages of a reconstruction for its report. The library itself reads no clock
/// and no allocator: without an observer the report's times and heap figures are zero.
pub trait Observer: Send {
    /// A stage starts (stages may run more than once; figures of one stage add up).
    fn stage_started(&mut self, stage: Stage);
    /// The stage that started last has ended.
    fn stage_finished(&mut self, stage: Stage) -> StageFigures;
}

/// An [`Observer`] of stage wall times only.
#[derive(Debug, Default)]
pub struct Clock {
    started: Option<Instant>,
}

impl Observer for Clock {
    fn stage_started(&mut self, _stage: Stage) {
        self.started = Some(Instant::now());
    }

    fn stage_finished(&mut self, _stage: Stage) -> StageFigures {
        StageFigures {
            time: self.started.take().map_or(Duration::ZERO, |t| t.elapsed()),
            heap_peak: 0,
        }
    }
}

/// Runs the stages of one reconstruction, recording each one's figures in `stats`.
pub(crate) struct Stages<'a> {
    pub stats: FrameStats,
    observer: Option<&'a mut dyn Observer>,
}

impl<'a> Stages<'a> {
    pub fn start(stats: FrameStats, observer: Option<&'a mut dyn Observer>) -> Stages<'a> {
        Stages { stats, observer }
    }

    pub fn run<T>(&mut self, stage: Stage, f: impl FnOnce() -> T) -> T {
        let Some(observer) = self.observer.as_deref_mut() else {
            return f();
        };
        observer.stage_started(stage);
        let out = f();
        let figures = observer.stage_finished(stage);
        let (t, h) = (&mut self.stats.timings, &mut self.stats.stage_heap);
        let (time, heap) = match stage {
            Stage::HandlerArray => (&mut t.handler_array, &mut h.handler_array),
            Stage::SurfaceParticles => (&mut t.surface_particles, &mut h.surface_particles),
            Stage::Band => (&mut t.band, &mut h.band),
            Stage::ScalarField => (&mut t.scalar_field, &mut h.scalar_field),
            Stage::Triangulation => (&mut t.triangulation, &mut h.triangulation),
            Stage::Post => (&mut t.post, &mut h.post),
        };
        *time += figures.time;
        *heap = (*heap).max(figures.heap_peak);
        out
    }
}

/// Peak heap bytes per stage, above the heap held when the reconstruction started (the input
/// particles are not counted). Each includes what earlier stages still hold.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct StageHeap {
    /// See [`Stage::HandlerArray`].
    pub handler_array: usize,
    /// See [`Stage::SurfaceParticles`].
    pub surface_particles: usize,
    /// See [`Stage::Band`].
    pub band: usize,
    /// See [`Stage::ScalarField`].
    pub scalar_field: usize,
    /// See [`Stage::Triangulation`].
    pub triangulation: usize,
    /// See [`Stage::Post`].
    pub post: usize,
}

impl StageHeap {
    /// The largest of the stages'.
    pub fn max(&self) -> usize {
        [
            self.handler_array,
            self.surface_particles,
            self.band,
            self.scalar_field,
            self.triangulation,
            self.post,
        ]
        .into_iter()
        .max()
        .unwrap_or(0)
    }
}

/// Counts and memory of one reconstructed frame.
#[derive(Debug, Clone, Copy, Default)]
pub struct FrameStats {
    /// Particle spacing r of the frame, in world units.
    pub spacing: f32,
    /// Marching Cubes cell size, in world units.
    pub cell: f32,
    /// Particles of the frame (inside the particle box, when one is given).
    pub particles: usize,
    /// Particles dropped for lying outside the particle box (set by callers that filter).
    pub particles_outside_box: usize,
    /// Surface particles (Sec. 4): 0 for the engines that do not look for them.
    pub surface_particles: usize,
    /// Bricks of 8³ vertices holding surface vertices.
    pub bricks: usize,
    /// Grid vertices that got a field value.
    pub surface_vertices: usize,
    /// Vertices added to close the band where the surface left it (included above).
    pub closure_vertices: usize,
    /// Vertices whose sign the field settled far from its surface and whose value no
    /// triangle read, so it was never computed (included above; SSP07 only).
    pub deferred_values: usize,
    /// Vertices whose value is the mean of the frame's field and its neighbour frames' where
    /// the fluid carries them (the ends of the crossed edges; `post.temporal` in a sequence).
    pub flow_mean_vertices: usize,
    /// Cells triangulated (the surface crosses them).
    pub surface_cells: usize,
    /// Triangles of the mesh.
    pub triangles: usize,
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Largest sum of the bytes held at once by the reconstruction's own arrays (handler array,
    /// band, field values, mesh), measured from their capacities.
    pub peak_bytes: usize,
    /// The heap the engine estimated it would need, checked against the memory limit before
    /// its big allocations (0 where it made no estimate: the slices engine before it ran).
    pub planned_bytes: u64,
    /// Peak heap of the reconstruction, the largest of the observer's stage figures (0 without
    /// an observer that measures heap).
    pub heap_peak: usize,
    /// Peak heap per stage, from the observer.
    pub stage_heap: StageHeap,
    /// Peak resident set size of the process after the frame (Linux's VmHWM), set by callers
    /// that measure it, else 0.
    pub peak_rss: u64,
    /// Vertices per axis of the full grid: the particles' box widened by the support.
    pub grid: [u64; 3],
    /// Worker threads of the pool that reconstructed the frame.
    pub threads: usize,
    /// Stage times, from the observer; read and write times from the caller.
    pub timings: Timings,
    /// The slices engine's blocks (zeros for the other engines).
    pub slices: SlicesFigures,
    /// The vertex correction of `correct` (zeros when it is off).
    pub correction: CorrectionFigures,
    /// The figures of an isosurface (`splash iso`) instead of a reconstruction's.
    pub iso: Option<crate::iso::stats::IsoStats>,
}

/// What the correction step (Marching Correctors, Sec. III-D2) did to the mesh's vertices:
/// shifts along their edges as fractions of the edge, and the field's |f − iso| at the
/// vertices before and after, in the field's units.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct CorrectionFigures {
    /// Vertices corrected (every vertex strictly inside its edge).
    pub vertices: usize,
    /// Vertices the correction moved.
    pub moved: usize,
    /// Mean and largest shift, in edge lengths.
    pub shift_mean: f64,
    /// See `shift_mean`.
    pub shift_max: f64,
    /// Mean and largest |f − iso| at the linearly interpolated vertices.
    pub residual_before_mean: f64,
    /// See `residual_before_mean`.
    pub residual_before_max: f64,
    /// Mean and largest |f − iso| at the corrected vertices.
    pub residual_after_mean: f64,
    /// See `residual_after_mean`.
    pub residual_after_max: f64,
}

impl fmt::Display for CorrectionFigures {
    /// Nothing when the correction is off.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.vertices == 0 {
            return Ok(());
        }
        write!(
            f,
            "; corrected {} of {} vertices: shift {:.3} mean, {:.3} max edge; |f − iso| \
             {:.2e} mean, {:.2e} max before, {:.2e} mean, {:.2e} max after",
            self.moved,
            self.vertices,
            self.shift_mean,
            self.shift_max,
            self.residual_before_mean,
            self.residual_before_max,
            self.residual_after_mean,
            self.residual_after_max
        )
    }
}

/// The Marching Slices engine's memory per block, as in Fig. 7 of Rosenberg & Birdwell 2008.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct SlicesFigures {
    /// Blocks marched.
    pub blocks: usize,
    /// Most slices cached at once in any block.
    pub peak_slices: usize,
    /// Largest and mean peak "render memory" of a block: slice and corner caches, todo lists.
    pub render_bytes_max: usize,
    /// See `render_bytes_max`.
    pub render_bytes_mean: usize,
    /// Largest and mean "cache memory" of a block: lookup cache and particle list.
    pub cache_bytes_max: usize,
    /// See `cache_bytes_max`.
    pub cache_bytes_mean: usize,
    /// Peak of both, summed over the blocks being marched at once.
    pub in_flight_peak: usize,
}

impl fmt::Display for SlicesFigures {
    /// Nothing for the engines without blocks.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.blocks == 0 {
            return Ok(());
        }
        let mb = |b: usize| b as f64 / 1e6;
        write!(
            f,
            "; {} blocks: render memory ≤ {:.2} MB (mean {:.2}), cache memory ≤ {:.2} MB \
             (mean {:.2}), ≤ {} slices, {:.1} MB in flight",
            self.blocks,
            mb(self.render_bytes_max),
            mb(self.render_bytes_mean),
            mb(self.cache_bytes_max),
            mb(self.cache_bytes_mean),
            self.peak_slices,
            mb(self.in_flight_peak)
        )
    }
}

impl FrameStats {
    /// Vertices of the full grid: the product of [`grid`](Self::grid).
    pub fn grid_vertices(&self) -> u64 {
        self.grid.iter().product()
    }
}

impl fmt::Display for FrameStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        let t = &self.timings;
        if let Some(iso) = &self.iso {
            return write!(
                f,
                "{} particles, {iso}; read {:.0} ms, write {:.0} ms; {:.1} MB peak RSS",
                self.particles,
                ms(t.read),
                ms(t.write),
                self.peak_rss as f64 / 1e6
            );
        }
        write!(
            f,
            "{} particles ({} surface{}), {} surface vertices, {} triangles; \
             read {:.0} ms, sort {:.0} ms, t_sp {:.0} ms, band {:.0} ms, t_sf {:.0} ms, \
             t_tri {:.0} ms, post {:.0} ms, write {:.0} ms; {:.1} MB arrays, {:.1} MB peak heap, {:.1} MB peak RSS{}{}",
            self.particles,
            self.surface_particles,
            if self.particles_outside_box > 0 {
                format!(
                    "; {} outside the particle box, dropped",
                    self.particles_outside_box
                )
            } else {
                String::new()
            },
            self.surface_vertices,
            self.triangles,
            ms(t.read),
            ms(t.handler_array),
            ms(t.surface_particles),
            ms(t.band),
            ms(t.scalar_field),
            ms(t.triangulation),
            ms(t.post),
            ms(t.write),
            self.peak_bytes as f64 / 1e6,
            self.heap_peak as f64 / 1e6,
            self.peak_rss as f64 / 1e6,
            self.slices,
            self.correction
        )
    }
}
