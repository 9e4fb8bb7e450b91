//! Memory figures: exact heap bytes from a counting global allocator, the process's peak
//! resident set size, and the machine's memory for the default `--max-memory`.
//!
//! The allocator counts every allocation of the process, on every thread; the figures of one
//! reconstruction are exact when nothing else allocates meanwhile (the `splash` CLI, one frame
//! at a time). With the `count-alloc` feature off (it is on by default) the heap figures read 0.

use std::sync::atomic::{AtomicUsize, Ordering};

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

    /// Heap above the start now.
    pub fn now(&self) -> usize {
        heap_now().saturating_sub(self.base)
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

/// Total memory of the machine in bytes (MemTotal of /proc/meminfo), if known.
pub fn machine_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    kib_field(&text, "MemTotal:").map(|k| k * 1024)
}

/// The default `--max-memory`: half the machine's memory, or 8 GiB where that is unknown.
pub fn default_limit() -> u64 {
    machine_memory().map_or(8 << 30, |m| m / 2)
}

fn status_kib(key: &str) -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    kib_field(&text, key)
}

fn kib_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    line[key.len()..].split_whitespace().next()?.parse().ok()
}

/// Parses a byte count as a user writes it: `12G`, `512M`, `1.5GB`, `800MiB`, `1000000`.
/// Suffixes are binary (K = 1024).
pub fn parse_bytes(text: &str) -> anyhow::Result<u64> {
    let t = text.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let number: f64 = number
        .trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("'{text}' is not a size: use e.g. 12G, 512M or 1000000"))?;
    let scale: u64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1,
        "k" | "kb" | "kib" => 1 << 10,
        "m" | "mb" | "mib" => 1 << 20,
        "g" | "gb" | "gib" => 1 << 30,
        "t" | "tb" | "tib" => 1 << 40,
        _ => anyhow::bail!("'{text}': unknown unit '{unit}' (use K, M, G or T)"),
    };
    if !(number.is_finite() && number >= 0.0) {
        anyhow::bail!("'{text}' is not a size");
    }
    Ok((number * scale as f64) as u64)
}

/// Bytes for people: `1.23 GB`, `45.6 MB` (decimal units, as the paper's tables).
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.2} GB", b / 1e9)
    } else if b >= 1e6 {
        format!("{:.1} MB", b / 1e6)
    } else {
        format!("{:.0} kB", b / 1e3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_bytes("1000").unwrap(), 1000);
        assert_eq!(parse_bytes("2K").unwrap(), 2048);
        assert_eq!(parse_bytes("1.5G").unwrap(), 3 << 29);
        assert_eq!(parse_bytes("512MiB").unwrap(), 512 << 20);
        assert!(parse_bytes("lots").is_err());
        assert!(parse_bytes("3X").is_err());
    }

    #[test]
    fn machine_figures_are_read() {
        if cfg!(target_os = "linux") {
            assert!(machine_memory().unwrap() > 1 << 20);
            assert!(peak_rss().unwrap() > 0);
        }
    }
}
