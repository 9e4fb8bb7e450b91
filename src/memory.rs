//! Memory figures: exact heap bytes from a counting global allocator, the process's peak
//! resident set size, and the [`Meter`] that gives both, and stage times, to the library's
//! reports.
//!
//! The allocator counts every allocation of the process, on every thread; the figures of one
//! reconstruction are exact when nothing else allocates meanwhile (the `splash` CLI, one frame
//! at a time). With the `count-alloc` feature off (it is on by default) the heap figures read 0.

use std::sync::atomic::{AtomicUsize, Ordering};

use std::path::Path;

use splash_sph::pipeline::{FrameOutcome, Plan, Progress};
use splash_sph::{
    Clock, FrameStats, Observer, Reconstruction, Reconstructor, Stage, StageFigures, Vec3,
};

/// Makes glibc give every allocation of 1 MiB or more its own mapping, returned to the system
/// when freed. By default glibc raises that threshold to the size of each large block freed (up
/// to 32 MiB), after which a frame's big arrays come from the heap and stay resident once
/// freed. Peak resident memory, 2 threads, r/2: cbd-large f23 91 -> 81 MiB with `--raw`, 103
/// -> 93 by default, 141 -> 110 with `refine_angle = 16`; the 21 cbd-small frames in one run
/// 28 -> 23 MiB; wall time 2-4 % longer (paired, within the machine's noise). At 128 KiB the
/// sequence took 6 % longer (more page faults); at 4 MiB it kept 26 of its 28 MiB.
/// The CLI only: the Python package leaves its host's allocator alone.
pub fn return_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets a parameter of glibc's allocator, before any thread starts.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
    }
}

static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

/// The system allocator, counting the bytes it holds and their peak.
pub struct CountingAlloc;

#[cfg(feature = "count-alloc")]
#[global_allocator]
static GLOBAL: CountingAlloc = CountingAlloc;

fn grew(bytes: usize) {
    let now = CURRENT.fetch_add(bytes, Ordering::Relaxed) + bytes;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

fn shrank(bytes: usize) {
    CURRENT.fetch_sub(bytes, Ordering::Relaxed);
}

// SAFETY: every call is forwarded to the system allocator unchanged; only counters are added.
unsafe impl std::alloc::GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        let p = unsafe { std::alloc::System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        let p = unsafe { std::alloc::System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        unsafe { std::alloc::System.dealloc(ptr, layout) };
        shrank(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new: usize) -> *mut u8 {
        let p = unsafe { std::alloc::System.realloc(ptr, layout, new) };
        if !p.is_null() {
            if new >= layout.size() {
                grew(new - layout.size());
            } else {
                shrank(layout.size() - new);
            }
        }
        p
    }
}

/// Whether the counting allocator is installed (heap figures are meaningful).
pub fn counting() -> bool {
    cfg!(feature = "count-alloc")
}

/// Heap bytes held by the process now.
pub fn heap_now() -> usize {
    CURRENT.load(Ordering::Relaxed)
}

/// Tracks the peak heap of a piece of work above the heap held when it started.
#[derive(Debug, Clone, Copy)]
pub struct HeapScope {
    base: usize,
}

impl HeapScope {
    /// Starts measuring; resets the process-wide peak to the current heap.
    pub fn start() -> HeapScope {
        let base = heap_now();
        PEAK.store(base, Ordering::Relaxed);
        HeapScope { base }
    }

    /// Peak heap above the start since the last [`start`](Self::start) or
    /// [`restart_peak`](Self::restart_peak).
    pub fn peak(&self) -> usize {
        PEAK.load(Ordering::Relaxed).saturating_sub(self.base)
    }

    /// Restarts the peak from the current heap, to measure one stage; the base is kept.
    pub fn restart_peak(&self) {
        PEAK.store(heap_now(), Ordering::Relaxed);
    }
}

/// The process's peak resident set size in bytes (VmHWM of /proc/self/status), if known.
pub fn peak_rss() -> Option<u64> {
    status_kib("VmHWM:").map(|k| k * 1024)
}

/// Resets the peak resident set size to the current one (Linux: `5` to /proc/self/clear_refs),
/// so that the next [`peak_rss`] covers only what follows. Returns whether it worked.
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

fn status_kib(key: &str) -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    kib_field(&text, key)
}

fn kib_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    line[key.len()..].split_whitespace().next()?.parse().ok()
}

/// Measures a reconstruction's stages for its report: wall time, and the peak heap above the
/// heap held when the meter was made (the input particles are not counted).
pub struct Meter {
    clock: Clock,
    heap: HeapScope,
}

impl Meter {
    pub fn start() -> Meter {
        Meter {
            clock: Clock::default(),
            heap: HeapScope::start(),
        }
    }
}

impl Observer for Meter {
    fn stage_started(&mut self, stage: Stage) {
        self.heap.restart_peak();
        self.clock.stage_started(stage);
    }

    fn stage_finished(&mut self, stage: Stage) -> StageFigures {
        StageFigures {
            heap_peak: self.heap.peak(),
            ..self.clock.stage_finished(stage)
        }
    }
}

/// Reconstructs with a [`Meter`], and records the process's peak resident set size after it.
pub fn reconstruct_measured(
    reconstructor: &Reconstructor,
    particles: &[Vec3],
) -> splash_sph::Result<Reconstruction> {
    let mut meter = Meter::start();
    let mut rec = reconstructor.reconstruct_observed(particles, &mut meter)?;
    rec.stats.peak_rss = peak_rss().unwrap_or(0);
    Ok(rec)
}

/// A run's progress with each frame measured: a [`Meter`] on every reconstruction, and the
/// process's peak resident set size once the frame's surface is made.
pub struct Metered<'a>(pub &'a mut dyn Progress);

impl Progress for Metered<'_> {
    fn started(&mut self, plan: &Plan) {
        self.0.started(plan);
    }

    fn spacing_estimated(&mut self, from: &Path, spacing: f32) {
        self.0.spacing_estimated(from, spacing);
    }

    fn warning(&mut self, input: Option<&Path>, message: &str) {
        self.0.warning(input, message);
    }

    fn frame_done(&mut self, outcome: &FrameOutcome, done: usize, total: usize) {
        self.0.frame_done(outcome, done, total);
    }

    fn observer(&mut self) -> Box<dyn Observer> {
        Box::new(Meter::start())
    }

    fn measured(&mut self, stats: &mut FrameStats) {
        stats.peak_rss = peak_rss().unwrap_or(0);
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use splash_sph::{Config, Engine, Length};

    use super::*;

    /// The heap figures of the engines at cells r and r/2. The counting allocator counts the
    /// whole test process; the other tests of this binary allocate kilobytes, these megabytes.
    #[test]
    fn memory_follows_the_cell_and_the_narrow_band_needs_least() {
        assert!(counting(), "the counting allocator is off");
        let fixture = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/frame_0040.ply");
        let ps = splash_sph::read_particles(Path::new(fixture), None)
            .unwrap()
            .positions;
        let reconstructor = |cell: &str, engine| {
            Reconstructor::new(Config {
                spacing: Some(0.014),
                cell: Length::parse(cell).unwrap(),
                engine,
                ..Config::default()
            })
            .unwrap()
        };
        let heap = |cell: &str, engine| {
            let s = reconstruct_measured(&reconstructor(cell, engine), &ps)
                .unwrap()
                .stats;
            // Every stage that ran holds something; the peak is the largest stage's.
            assert!(s.stage_heap.scalar_field > 0 && s.stage_heap.triangulation > 0);
            assert_eq!(s.heap_peak, s.stage_heap.max());
            assert!(s.peak_rss as usize > s.heap_peak);
            s.heap_peak
        };
        let mut at_half = Vec::new();
        for engine in [Engine::NarrowBand, Engine::FullGather, Engine::Scatter] {
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
        // The estimate that --max-memory checks covers the grid and a guess of the mesh: it
        // is an upper bound, and not a loose one.
        for (engine, measured) in [(Engine::FullGather, gather), (Engine::Scatter, scatter)] {
            let need = reconstructor("r/2", engine)
                .planned_memory(&ps)
                .unwrap()
                .unwrap() as f64;
            let ratio = measured as f64 / need;
            assert!(
                (0.5..1.05).contains(&ratio),
                "{engine:?}: measured/estimate {ratio}"
            );
        }
    }

    #[test]
    fn machine_figures_are_read() {
        if cfg!(target_os = "linux") {
            assert!(peak_rss().unwrap() > 0);
        }
    }
}
