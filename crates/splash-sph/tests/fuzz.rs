//! Fuzzing on the stable toolchain: every particle and mesh reader, the configuration parsers
//! and the reconstruction get mutated inputs from a seeded generator, and must neither panic nor
//! allocate beyond what the input's size justifies; errors must name the file and stay short;
//! the same input must give the same result.
//!
//! - `cargo test --release --test fuzz` runs a few thousand cases (the CI budget).
//! - `SPLASH_FUZZ_CASES=N` runs N cases per reader and per configuration target (4N lengths and
//!   sizes, N/20 reconstructions); `SPLASH_FUZZ_TARGET=csv` only the targets whose name holds
//!   that text; `SPLASH_FUZZ_SEED=S` another seed (a failure prints the seed and case that
//!   replay it).
//! - A failing input is saved under `tests/fuzz-corpus/<target>/` (beside this file), and every
//!   file there is replayed by its target on every run: commit it with the fix.
//!
//! A new reader is one line of [`READERS`]: its name, its extension, how to read a path, and
//! its seeds (small valid files, and the broken ones its tests know).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::{Cell, RefCell};
use std::fmt::Write as _;
use std::fs;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::Vec3;
use splash_sph::io::{MeshFormat, VertexAttributes, read_mesh, write_mesh_with};
use splash_sph::mesh::TriMesh;
use splash_sph::{
    Attribute, Bytes, Config, Engine, Error, Length, Particles, Reconstructor, read_particles,
};

// ---------------------------------------------------------------------------------------------
// The targets.

/// A particle reader under test.
struct Reader {
    name: &'static str,
    /// The extension of the files it is given (the path is all a reader sees).
    extension: &'static str,
    read: fn(&Path) -> splash_sph::Result<Particles>,
    seeds: fn() -> Vec<Vec<u8>>,
}

/// Reads by the file's extension, as `splash recon` does.
fn by_extension(path: &Path) -> splash_sph::Result<Particles> {
    read_particles(path, None)
}

/// Reads a mesh (`io::read_mesh`): its vertices as the positions, its normals (when it has
/// them), triangles' corners and vertex attributes as attributes, so that every part of it
/// is checked and fingerprinted.
fn mesh(path: &Path) -> splash_sph::Result<Particles> {
    let file = read_mesh(path)?;
    let mut attributes = file.attributes;
    if !file.mesh.normals.is_empty() {
        attributes.insert("(normals)".into(), Attribute::Vector(file.mesh.normals));
    }
    // The corners cycled to one per vertex: an attribute is as long as the vertices.
    if !file.mesh.triangles.is_empty() {
        let corners = file.mesh.triangles.iter().flatten().cycle();
        let corners = corners.take(file.mesh.vertices.len());
        let corners = corners.map(|&c| c as f32).collect();
        attributes.insert("(corners)".into(), Attribute::Scalar(corners));
    }
    Ok(Particles {
        positions: file.mesh.vertices,
        attributes,
    })
}

#[rustfmt::skip]
const READERS: &[Reader] = &[
    Reader { name: "ply-ascii", extension: "ply", read: by_extension, seeds: ply_ascii_seeds },
    Reader { name: "ply-le", extension: "ply", read: by_extension, seeds: ply_le_seeds },
    Reader { name: "ply-be", extension: "ply", read: by_extension, seeds: ply_be_seeds },
    Reader { name: "csv", extension: "csv", read: by_extension, seeds: csv_seeds },
    Reader { name: "raw", extension: "bin", read: by_extension, seeds: raw_seeds },
    Reader { name: "vtk", extension: "vtk", read: by_extension, seeds: vtk_seeds },
    Reader { name: "vtu", extension: "vtu", read: by_extension, seeds: vtu_seeds },
    Reader { name: "vtp", extension: "vtp", read: by_extension, seeds: vtp_seeds },
    Reader { name: "bgeo", extension: "bgeo", read: by_extension, seeds: bgeo_seeds },
    Reader { name: "xyz", extension: "xyz", read: by_extension, seeds: xyz_seeds },
    Reader { name: "mesh-obj", extension: "obj", read: mesh, seeds: obj_mesh_seeds },
    Reader { name: "mesh-ply", extension: "ply", read: mesh, seeds: ply_mesh_seeds },
    Reader { name: "mesh-vtk", extension: "vtk", read: mesh, seeds: vtk_mesh_seeds },
    Reader { name: "mesh-vtu", extension: "vtu", read: mesh, seeds: vtu_mesh_seeds },
    Reader { name: "mesh-vtp", extension: "vtp", read: mesh, seeds: vtp_mesh_seeds },
];

/// Cases per reader in the default (CI) mode.
const DEFAULT_CASES: u64 = 1000;

// ---------------------------------------------------------------------------------------------
// Settings from the environment.

fn env_u64(name: &str) -> Option<u64> {
    let text = std::env::var(name).ok()?;
    let text = text.trim();
    let parsed = match text.strip_prefix("0x") {
        Some(hex) => u64::from_str_radix(hex, 16),
        None => text.parse(),
    };
    Some(parsed.unwrap_or_else(|_| panic!("{name}={text} is not a number")))
}

/// Cases per target, scaled from the reader count by `percent`.
fn cases(percent: u64) -> u64 {
    let base = env_u64("SPLASH_FUZZ_CASES").unwrap_or(DEFAULT_CASES);
    (base * percent / 100).max(1)
}

fn base_seed() -> u64 {
    env_u64("SPLASH_FUZZ_SEED").unwrap_or(0x5eed_5a1a_5b00_0014)
}

fn selected(target: &str) -> bool {
    std::env::var("SPLASH_FUZZ_TARGET").map_or(true, |f| f.split(',').any(|f| target.contains(f)))
}

// ---------------------------------------------------------------------------------------------
// A seeded generator (SplitMix64): fast, and the same cases on every machine.

struct Rng(u64);

impl Rng {
    fn new(seed: u64, target: &str, case: u64) -> Self {
        let mut h = seed ^ 0x9e37_79b9_7f4a_7c15;
        for b in target.bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
        }
        let mut rng = Rng(h ^ case.wrapping_mul(0xd1b5_4a32_d192_ed03));
        rng.next();
        rng
    }

    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in 0..n (n > 0).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }

    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

// ---------------------------------------------------------------------------------------------
// Heap accounting: a counting allocator, per thread, so that parallel tests do not mix. A case
// arms a budget; the peak above the case's start is checked against it afterwards, and a
// single request beyond the hard cap is refused with a message naming the case (on stable Rust
// a failed allocation aborts: the message is what is left to go on).

struct Counting;

thread_local! {
    static LIVE: Cell<usize> = const { Cell::new(0) };
    static PEAK: Cell<usize> = const { Cell::new(0) };
    static ARMED: Cell<bool> = const { Cell::new(false) };
    static CASE: RefCell<String> = const { RefCell::new(String::new()) };
}

/// No single allocation of a case may ask for more than this.
const HARD_CAP: usize = 1 << 30;

impl Counting {
    fn grow(size: usize) {
        let _ = LIVE.try_with(|live| {
            let now = live.get().wrapping_add(size);
            live.set(now);
            let _ = PEAK.try_with(|peak| {
                if (now as isize) > (peak.get() as isize) {
                    peak.set(now);
                }
            });
        });
    }

    fn shrink(size: usize) {
        let _ = LIVE.try_with(|live| live.set(live.get().wrapping_sub(size)));
    }

    fn refuse(size: usize) -> bool {
        if size <= HARD_CAP || !ARMED.try_with(Cell::get).unwrap_or(false) {
            return false;
        }
        ARMED.with(|armed| armed.set(false));
        let case = CASE.with(|c| c.borrow().clone());
        eprintln!("fuzz: {case} asked for one allocation of {size} bytes; refused (abort follows)");
        true
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if Self::refuse(layout.size()) {
            return std::ptr::null_mut();
        }
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            Self::grow(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if Self::refuse(layout.size()) {
            return std::ptr::null_mut();
        }
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            Self::grow(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        Self::shrink(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > layout.size() && Self::refuse(new_size) {
            return std::ptr::null_mut();
        }
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            Self::shrink(layout.size());
            Self::grow(new_size);
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Runs `f` as case `name`, returning its result (or the panic's message) and the peak of this
/// thread's heap above its start.
fn measured<T>(name: &str, f: impl FnOnce() -> T) -> (Result<T, String>, usize) {
    CASE.with(|c| {
        let mut c = c.borrow_mut();
        c.clear();
        c.push_str(name);
    });
    let start = LIVE.with(Cell::get);
    PEAK.with(|p| p.set(start));
    ARMED.with(|a| a.set(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    ARMED.with(|a| a.set(false));
    let peak = PEAK.with(Cell::get).wrapping_sub(start);
    let result = result.map_err(|payload| {
        payload
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "a panic".into())
    });
    (result, peak)
}

/// The accounting sees a case's allocations, and only the peak above the case's start.
#[test]
fn the_heap_is_counted() {
    let before = vec![0u8; 4 << 20];
    let (result, peak) = measured("self-test", || vec![1u8; 10 << 20].len());
    assert_eq!(result, Ok(10 << 20));
    assert!((10 << 20..11 << 20).contains(&peak), "{peak}");
    let (_, peak) = measured("self-test", || before.len());
    assert!(peak < 1 << 10, "{peak}");
}

// ---------------------------------------------------------------------------------------------
// The run: seeds, mutants, the properties, failures saved.

/// Error messages, without the file's path, are at most this long.
const MAX_MESSAGE: usize = 300;

/// Slower than this is a failure (a scan of a declared count, a quadratic loop).
const MAX_CASE_TIME: Duration = Duration::from_secs(5);

/// Heap a read may use: a multiple of the file, and the readers' fixed buffers (64 KiB
/// readers, 1 MiB chunks and lines). The largest factor found is a CSV header of empty names
/// (one comma each: ~65 bytes of names and columns per byte); what the bound catches is an
/// allocation that follows a declared count rather than the bytes present.
fn read_budget(file_len: usize) -> usize {
    128 * file_len + (8 << 20)
}

fn corpus_dir(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz-corpus")
        .join(target)
}

/// The files of a target's corpus, sorted.
fn corpus(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let Ok(entries) = fs::read_dir(corpus_dir(target)) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = entries.filter_map(|e| Some(e.ok()?.path())).collect();
    files.sort();
    files
        .into_iter()
        .filter(|p| p.is_file())
        .map(|p| {
            let bytes = fs::read(&p).unwrap();
            (p, bytes)
        })
        .collect()
}

/// Saves a failing input in the target's corpus; returns its path.
fn save_failure(target: &str, extension: &str, input: &[u8]) -> PathBuf {
    let dir = corpus_dir(target);
    fs::create_dir_all(&dir).unwrap();
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in input {
        hash = (hash ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
    }
    let path = dir.join(format!("{hash:016x}.{extension}"));
    fs::write(&path, input).unwrap();
    path
}

/// The outcome of one read, in a form that compares bit for bit.
fn fingerprint(result: &splash_sph::Result<Particles>) -> String {
    match result {
        Err(e) => format!("Err({e})"),
        Ok(p) => {
            let mut out = String::new();
            for v in &p.positions {
                let _ = write!(
                    out,
                    "{:x},{:x},{:x};",
                    v.x.to_bits(),
                    v.y.to_bits(),
                    v.z.to_bits()
                );
            }
            for (name, attribute) in &p.attributes {
                let _ = write!(out, "|{name}:");
                match attribute {
                    Attribute::Scalar(v) => v.iter().for_each(|x| {
                        let _ = write!(out, "{:x},", x.to_bits());
                    }),
                    Attribute::Vector(v) => v.iter().for_each(|x| {
                        let _ = write!(
                            out,
                            "{:x}/{:x}/{:x},",
                            x.x.to_bits(),
                            x.y.to_bits(),
                            x.z.to_bits()
                        );
                    }),
                }
            }
            out
        }
    }
}

/// Checks one read of `path` (holding `input`); the violated property, if any.
fn check_read(reader: &Reader, path: &Path, input: &[u8], case: &str) -> Option<String> {
    let started = Instant::now();
    let (result, peak) = measured(case, || (reader.read)(path));
    let elapsed = started.elapsed();
    let result = match result {
        Ok(result) => result,
        Err(panic) => return Some(format!("panicked: {panic}")),
    };
    if elapsed > MAX_CASE_TIME {
        return Some(format!("took {elapsed:?}"));
    }
    let budget = read_budget(input.len());
    if peak > budget {
        return Some(format!(
            "used {peak} bytes of heap for a file of {} bytes (budget {budget})",
            input.len()
        ));
    }
    match &result {
        Ok(particles) => {
            if let Some(p) = particles.positions.iter().find(|p| !p.is_finite()) {
                return Some(format!("returned a non-finite position {p}"));
            }
            for (name, attribute) in &particles.attributes {
                let len = match attribute {
                    Attribute::Scalar(v) => v.len(),
                    Attribute::Vector(v) => v.len(),
                };
                if len != particles.len() {
                    return Some(format!(
                        "attribute '{name}' has {len} values for {} particles",
                        particles.len()
                    ));
                }
            }
        }
        Err(e) => {
            if !matches!(
                e,
                Error::Format { .. } | Error::MeshFormat { .. } | Error::Io { .. }
            ) {
                return Some(format!("returned an error of the wrong kind: {e:?}"));
            }
            let text = e.to_string();
            let name = path.file_name().unwrap().to_string_lossy();
            if !text.contains(&*name) {
                return Some(format!("error does not name the file: {text}"));
            }
            let own = text.replace(&*path.to_string_lossy(), "").chars().count();
            if own > MAX_MESSAGE {
                let excerpt: String = text.chars().take(400).collect();
                return Some(format!("error of {own} characters: {excerpt}…"));
            }
        }
    }
    let (again, _) = measured(case, || (reader.read)(path));
    match again {
        Ok(again) if fingerprint(&again) == fingerprint(&result) => None,
        Ok(_) => Some("a second read of the same file gave another result".into()),
        Err(panic) => Some(format!("panicked on the second read: {panic}")),
    }
}

/// Fuzzes one reader; returns (cases run, failures).
fn fuzz_reader(reader: &Reader, dir: &Path) -> (u64, Vec<String>) {
    let mut seeds = (reader.seeds)();
    let replay = corpus(reader.name);
    let mut failures = Vec::new();
    let path = dir.join(format!("{}-case.{}", reader.name, reader.extension));
    for (file, bytes) in &replay {
        fs::write(&path, bytes).unwrap();
        let case = format!("{} corpus file {}", reader.name, file.display());
        if let Some(why) = check_read(reader, &path, bytes, &case) {
            failures.push(format!("{case}: {why}"));
        }
    }
    seeds.extend(replay.into_iter().map(|(_, bytes)| bytes));
    let seed = base_seed();
    let n = cases(100);
    for case in 0..n {
        let mut rng = Rng::new(seed, reader.name, case);
        let input = if case < seeds.len() as u64 {
            seeds[case as usize].clone()
        } else {
            let mut input = rng.pick(&seeds).clone();
            for _ in 0..1 + rng.below(4) {
                mutate(&mut input, &seeds, &mut rng);
            }
            input
        };
        fs::write(&path, &input).unwrap();
        let name = format!(
            "{} case {case} (SPLASH_FUZZ_SEED={seed:#x} SPLASH_FUZZ_TARGET={})",
            reader.name, reader.name
        );
        if let Some(why) = check_read(reader, &path, &input, &name) {
            let saved = save_failure(reader.name, reader.extension, &input);
            failures.push(format!("{name}: {why}; input saved as {}", saved.display()));
            if failures.len() >= 20 {
                break;
            }
        }
    }
    (n, failures)
}

#[test]
fn readers() {
    let dir = std::env::temp_dir().join(format!("splash-fuzz-{}", std::process::id()));
    fs::create_dir_all(&dir).unwrap();
    let mut failures = Vec::new();
    for reader in READERS.iter().filter(|r| selected(r.name)) {
        let started = Instant::now();
        let (n, found) = fuzz_reader(reader, &dir);
        eprintln!(
            "fuzz: {}: {n} cases, {} failures, {:.1} s",
            reader.name,
            found.len(),
            started.elapsed().as_secs_f64()
        );
        failures.extend(found);
    }
    let _ = fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

// ---------------------------------------------------------------------------------------------
// Mutations.

const NUMBERS: &[&str] = &[
    "0",
    "-1",
    "1",
    "2",
    "255",
    "256",
    "65536",
    "2147483647",
    "2147483648",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999999999",
    "1e38",
    "3.5e38",
    "1e39",
    "-1e39",
    "1e-45",
    "1e-50",
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-inf",
    "infinity",
    "-0",
    "0x10",
    "1_000",
    "+5",
    ".",
    "-",
    "1e",
    "1.2.3",
    "",
    "\"1\"",
];

const WORDS: &[&str] = &[
    "char",
    "uchar",
    "short",
    "ushort",
    "int",
    "uint",
    "float",
    "double",
    "int8",
    "uint8",
    "int16",
    "uint16",
    "int32",
    "uint32",
    "float32",
    "float64",
    "list uchar int",
    "list int float",
    "list float int",
    "list uint uint",
    "list char double",
    "flaot",
    "vertex",
    "face",
    "element",
    "property",
    "x",
    "y",
    "z",
    "vx",
    "density",
    "ascii",
    "binary_little_endian",
    "binary_big_endian",
    "binary",
    "format",
    "comment",
    "end_header",
    "obj_info",
    "ply",
    "1.0",
    "2.0",
    "0.9",
];

/// Raw values for binary payloads: special floats and large list lengths or counts.
const VALUES: &[[u8; 4]] = &[
    [0x7f, 0xc0, 0, 0],       // NaN (big-endian view)
    [0, 0, 0xc0, 0x7f],       // NaN (little-endian)
    [0x7f, 0x80, 0, 0],       // +inf
    [0, 0, 0x80, 0x7f],       // +inf
    [0xff, 0x7f, 0xff, 0xff], // -f32::MAX and friends
    [0xff, 0xff, 0xff, 0xff],
    [0xff, 0xff, 0xff, 0x7f],
    [0, 0, 0, 0x80],
    [0, 0, 0, 1],
    [1, 0, 0, 0],
];

/// Offset where a PLY payload starts (after `end_header\n`), or 0.
fn payload_start(bytes: &[u8]) -> usize {
    bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .map_or(0, |p| p + 11)
}

fn line_starts(bytes: &[u8], limit: usize) -> Vec<usize> {
    let mut starts = vec![0];
    for (i, &b) in bytes.iter().enumerate().take(limit) {
        if b == b'\n' && i + 1 < bytes.len() {
            starts.push(i + 1);
        }
    }
    starts
}

fn line_end(bytes: &[u8], start: usize) -> usize {
    bytes[start..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |p| start + p)
}

fn mutate(input: &mut Vec<u8>, seeds: &[Vec<u8>], rng: &mut Rng) {
    let len = input.len();
    let at = |rng: &mut Rng| if len == 0 { 0 } else { rng.below(len) };
    match rng.below(17) {
        // Bit flip.
        0 if len > 0 => {
            let i = at(rng);
            input[i] ^= 1 << rng.below(8);
        }
        // An interesting byte.
        1 if len > 0 => {
            let i = at(rng);
            input[i] = *rng.pick(&[
                0, 0xff, b'\n', b'\r', b' ', b'-', b'.', b'e', b'9', 0x80, b',', b'"', b'#',
            ]);
        }
        // Insert bytes.
        2 => {
            let i = if len == 0 { 0 } else { rng.below(len + 1) };
            let n = 1 + rng.below(8);
            let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
            input.splice(i..i, bytes);
        }
        // Delete a range.
        3 if len > 0 => {
            let i = at(rng);
            let n = 1 + rng.below(16.min(len - i));
            input.drain(i..i + n);
        }
        // Truncate.
        4 if len > 0 => input.truncate(at(rng)),
        // Duplicate a range.
        5 if len > 0 => {
            let i = at(rng);
            let n = 1 + rng.below(64.min(len - i));
            let copy = input[i..i + n].to_vec();
            let j = rng.below(len + 1);
            input.splice(j..j, copy);
        }
        // Edit a header (or first) line: a word or number replaced, the line doubled, dropped or
        // moved.
        6..=8 => {
            let limit = match payload_start(input) {
                0 => 512.min(len),
                end => end,
            };
            let starts = line_starts(input, limit);
            let start = *rng.pick(&starts);
            let end = line_end(input, start);
            let line = String::from_utf8_lossy(&input[start..end]).into_owned();
            let mut words: Vec<String> = line.split(' ').map(String::from).collect();
            let new = match rng.below(6) {
                0 | 1 => {
                    let w = rng.below(words.len());
                    words[w] = rng.pick(NUMBERS).to_string();
                    words.join(" ")
                }
                2 => {
                    let w = rng.below(words.len());
                    words[w] = rng.pick(WORDS).to_string();
                    words.join(" ")
                }
                3 => format!("{line}\n{line}"),
                4 => String::new(),
                _ => {
                    let w = rng.below(words.len());
                    words.insert(w, rng.pick(WORDS).to_string());
                    words.join(" ")
                }
            };
            input.splice(start..end, new.into_bytes());
        }
        // A number anywhere in text replaced.
        9 if len > 0 => {
            let i = at(rng);
            let is_token = |b: u8| !b" \t\r\n,;".contains(&b);
            let mut start = i;
            while start > 0 && is_token(input[start - 1]) {
                start -= 1;
            }
            let mut end = i;
            while end < len && is_token(input[end]) {
                end += 1;
            }
            input.splice(start..end, rng.pick(NUMBERS).bytes());
        }
        // A binary value replaced: special floats, huge counts.
        10 if len >= 4 => {
            let i = rng.below(len - 3);
            let value: &[u8; 4] = rng.pick(VALUES);
            input[i..i + 4].copy_from_slice(value);
        }
        // A long line.
        11 => {
            let n = match rng.below(10) {
                0 => (1 << 20) + rng.below(64),
                1..=3 => 70_000,
                _ => 1 + rng.below(5000),
            };
            let byte = *rng.pick(b"0a ,\0\r9-".as_slice());
            let i = if len == 0 { 0 } else { rng.below(len + 1) };
            input.splice(i..i, std::iter::repeat_n(byte, n));
        }
        // Line ends: CR only, CRLF, none.
        12 => {
            let text = std::mem::take(input);
            *input = match rng.below(3) {
                0 => text
                    .iter()
                    .map(|&b| if b == b'\n' { b'\r' } else { b })
                    .collect(),
                1 => text
                    .iter()
                    .flat_map(|&b| {
                        if b == b'\n' {
                            vec![b'\r', b'\n']
                        } else {
                            vec![b]
                        }
                    })
                    .collect(),
                _ => text.into_iter().filter(|&b| b != b'\n').collect(),
            };
        }
        // NULs.
        13 => {
            let i = if len == 0 { 0 } else { rng.below(len + 1) };
            let n = 1 + rng.below(32);
            input.splice(i..i, std::iter::repeat_n(0, n));
        }
        // A column (field of the first line) duplicated.
        14 => {
            let end = line_end(input, 0);
            let line = String::from_utf8_lossy(&input[..end]).into_owned();
            let sep = [',', ';', ' ']
                .into_iter()
                .find(|&c| line.contains(c))
                .unwrap_or(',');
            let mut fields: Vec<&str> = line.split(sep).collect();
            let f = rng.below(fields.len());
            fields.insert(rng.below(fields.len() + 1), fields[f]);
            let new = fields.join(&sep.to_string());
            input.splice(..end, new.into_bytes());
        }
        // Splice with another seed.
        15 => {
            let other = rng.pick(seeds);
            let cut = if len == 0 { 0 } else { rng.below(len + 1) };
            let from = if other.is_empty() {
                0
            } else {
                rng.below(other.len())
            };
            input.truncate(cut);
            input.extend_from_slice(&other[from..]);
        }
        // A whole payload repeated (a count too small for the data).
        _ => {
            let start = payload_start(input);
            let copy = input[start..].to_vec();
            input.extend_from_slice(&copy);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Seeds: small valid files per format, the fixture's first records, broken files from the
// reader tests.

/// Values of scalar type `ty` in a PLY payload.
fn encode(ty: &str, value: f64, encoding: &str, out: &mut Vec<u8>) {
    macro_rules! put {
        ($t:ty) => {{
            let v = value as $t;
            match encoding {
                "ascii" => out.extend(format!("{v} ").bytes()),
                "binary_little_endian" => out.extend(v.to_le_bytes()),
                _ => out.extend(v.to_be_bytes()),
            }
        }};
    }
    match ty {
        "char" => put!(i8),
        "uchar" => put!(u8),
        "short" => put!(i16),
        "ushort" => put!(u16),
        "int" => put!(i32),
        "uint" => put!(u32),
        "double" => put!(f64),
        _ => put!(f32),
    }
}

/// Properties as (type, name), a list's type as `list uchar int`.
type Props<'a> = &'a [(&'a str, &'a str)];

/// A PLY file: `elements` are (name, properties, rows).
fn ply(encoding: &str, elements: &[(&str, Props, usize)]) -> Vec<u8> {
    let mut out = format!("ply\nformat {encoding} 1.0\ncomment fuzz seed\n");
    for (name, props, count) in elements {
        let _ = writeln!(out, "element {name} {count}");
        for (ty, prop) in *props {
            let _ = writeln!(out, "property {ty} {prop}");
        }
    }
    out.push_str("end_header\n");
    let mut out = out.into_bytes();
    for (_, props, count) in elements {
        for row in 0..*count {
            for (k, (ty, _)) in props.iter().enumerate() {
                let value = (row * 7 + k * 3) as f64 * 0.25 - 1.0;
                if let Some(list) = ty.strip_prefix("list ") {
                    let (len_ty, item_ty) = list.split_once(' ').unwrap();
                    let n = row % 3;
                    encode(len_ty, n as f64, encoding, &mut out);
                    for i in 0..n {
                        encode(item_ty, i as f64, encoding, &mut out);
                    }
                } else {
                    let value = if ty.contains('u') { value.abs() } else { value };
                    encode(ty, value, encoding, &mut out);
                }
            }
            if encoding == "ascii" {
                out.pop();
                out.push(b'\n');
            }
        }
    }
    out
}

const XYZ: &[(&str, &str)] = &[("float", "x"), ("float", "y"), ("float", "z")];

/// The first `n` vertices of the bundled frame (x y z vx vy vz density, floats).
fn fixture_rows(n: usize) -> Vec<[f32; 7]> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/frame_0010.ply");
    let bytes = fs::read(path).unwrap();
    let start = payload_start(&bytes);
    bytes[start..]
        .chunks_exact(28)
        .take(n)
        .map(|r| {
            std::array::from_fn(|k| f32::from_le_bytes(r[4 * k..4 * k + 4].try_into().unwrap()))
        })
        .collect()
}

/// The fixture's first vertices in `encoding`, with its header (count rewritten).
fn fixture_ply(encoding: &str, n: usize) -> Vec<u8> {
    let rows = fixture_rows(n);
    let mut out = format!(
        "ply\nformat {encoding} 1.0\ncomment SPlisHSPlasH 2.19.0 DFSPH fluid particles\n\
         element vertex {}\n",
        rows.len()
    );
    for name in ["x", "y", "z", "vx", "vy", "vz", "density"] {
        let _ = writeln!(out, "property float {name}");
    }
    out.push_str("end_header\n");
    let mut out = out.into_bytes();
    for row in rows {
        for v in row {
            encode("float", f64::from(v), encoding, &mut out);
        }
        if encoding == "ascii" {
            out.pop();
            out.push(b'\n');
        }
    }
    out
}

fn ply_seeds(encoding: &str) -> Vec<Vec<u8>> {
    let typed: &[(&str, &str)] = &[
        ("uchar", "flags"),
        ("double", "z"),
        ("short", "x"),
        ("float", "density"),
        ("int", "y"),
        ("char", "c"),
        ("ushort", "u"),
        ("uint", "id"),
    ];
    let listed: &[(&str, &str)] = &[
        ("float", "x"),
        ("list uchar int", "neighbours"),
        ("float", "y"),
        ("float", "z"),
        ("float", "vx"),
        ("float", "vy"),
        ("float", "vz"),
    ];
    let material: &[(&str, &str)] = &[("list uchar float", "rgb"), ("int", "id")];
    let face: &[(&str, &str)] = &[("list uchar int", "vertex_indices")];
    let mut seeds = vec![
        fixture_ply(encoding, 3),
        fixture_ply(encoding, 1),
        ply(encoding, &[("vertex", XYZ, 4)]),
        ply(encoding, &[("vertex", XYZ, 0)]),
        ply(encoding, &[("vertex", typed, 3)]),
        ply(encoding, &[("vertex", listed, 4)]),
        ply(
            encoding,
            &[
                ("material", material, 2),
                ("vertex", XYZ, 3),
                ("face", face, 2),
            ],
        ),
        ply(encoding, &[("empty", &[], 2), ("vertex", XYZ, 2)]),
    ];
    // Broken headers and payloads, as the reader tests build them.
    let header = |count: &str, props: &str| {
        format!("ply\nformat {encoding} 1.0\nelement vertex {count}\n{props}end_header\n")
    };
    let xyz = "property float x\nproperty float y\nproperty float z\n";
    let payload = ply(encoding, &[("vertex", XYZ, 4)]);
    let payload = &payload[payload_start(&payload)..];
    for (count, props) in [
        ("10000000000000", xyz.to_string()),
        ("5", xyz.to_string()),
        ("2", xyz.to_string()),
        (
            "4",
            "property float x\nproperty flaot y\nproperty float z\n".into(),
        ),
        (
            "4",
            "property float x\nproperty float x\nproperty float y\n".into(),
        ),
        (
            "4",
            "property list uchar float x\nproperty float y\nproperty float z\n".into(),
        ),
        ("4", format!("property list float int n\n{xyz}")),
        (
            "10000000000000",
            format!("property list uchar int n\n{xyz}"),
        ),
        ("1", format!("property list char int n\n{xyz}")),
    ] {
        seeds.push([header(count, &props).as_bytes(), payload].concat());
    }
    seeds.push(b"ply\nformat ascii 1.0\nelement vertex 1\n".to_vec());
    seeds.push(b"ply\nelement vertex 0\nend_header\n".to_vec());
    seeds.push(
        format!("ply\nformat {encoding} 2.0\nelement vertex 0\n{xyz}end_header\n").into_bytes(),
    );
    seeds
}

fn ply_ascii_seeds() -> Vec<Vec<u8>> {
    let mut seeds = ply_seeds("ascii");
    let header = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                  property float z\nend_header\n";
    for body in [
        "1 2 3\n4 abc 6\n",
        "1 2\n",
        "1 inf 3\n4 5 6\n",
        "0 1 2\n3 4 5 9\n",
        "1 2 3\n\n\n4 5 6\n",
    ] {
        seeds.push(format!("{header}{body}").into_bytes());
    }
    seeds.push(
        format!("{header}1 2 3\r\n4 5 6\r\n")
            .replace('\n', "\r\n")
            .into_bytes(),
    );
    seeds
}

fn ply_le_seeds() -> Vec<Vec<u8>> {
    ply_seeds("binary_little_endian")
}

fn ply_be_seeds() -> Vec<Vec<u8>> {
    ply_seeds("binary_big_endian")
}

fn csv_seeds() -> Vec<Vec<u8>> {
    let mut fixture = String::from("x,y,z,vx,vy,vz,density\n");
    for row in fixture_rows(4) {
        let fields: Vec<String> = row.iter().map(f32::to_string).collect();
        fixture.push_str(&fields.join(","));
        fixture.push('\n');
    }
    [
        fixture.as_str(),
        "x,y,z\n1,2,3\n4,5,6\n",
        "1,2,3\n4,5,6\n",
        "1 2 3\n4 5 6\n",
        "x;y;z;density\n1;2;3;1000\n4;5;6;999\n",
        "\u{feff}# a comment\n\"x\",\"y\",\"z\",\"pressure\"\r\n1,2,3,4\r\n\r\n5,6,7,8\r\n",
        "id\tX\tY\tZ\tnx\tny\tnz\tname\n1\t0.5\t0.5\t0.5\t0\t0\t1\tfoo\n2\t1\t1\t1\t1\t0\t0\tbar\n",
        "velocity_x,velocity_y,velocity_z,x,y,z,velocity\n1,2,3,4,5,6,7\n",
        "x,y,z\n",
        "",
        // Broken, as the reader tests have them.
        "x,y,z\n1,2,3\n4,abc,6\n",
        "1,2,3\n\n4,5\n",
        "# comment\nx,y,w\n1,2,3\n",
        "x y z\n1 NaN 3\n",
        "x,x,y,z\n1,2,3,4\n",
        "x;y;z\r1;2;3\r4;5;6\r",
    ]
    .iter()
    .map(|s| s.as_bytes().to_vec())
    .chain([b"x,y,z\n1,2,\xe9\n".to_vec()])
    .collect()
}

/// The interchange fixtures (written by VTK, numpy and a partio-layout script) whose names
/// end in `suffix`.
fn format_fixtures(suffix: &str) -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/formats");
    let mut names: Vec<PathBuf> = fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| Some(e.ok()?.path()))
        .filter(|p| p.to_string_lossy().ends_with(suffix))
        .collect();
    names.sort();
    assert!(!names.is_empty(), "no fixtures/formats/*{suffix}");
    names.iter().map(|p| fs::read(p).unwrap()).collect()
}

fn vtk_seeds() -> Vec<Vec<u8>> {
    format_fixtures(".vtk")
}

fn vtu_seeds() -> Vec<Vec<u8>> {
    format_fixtures(".vtu")
}

fn vtp_seeds() -> Vec<Vec<u8>> {
    format_fixtures(".vtp")
}

fn bgeo_seeds() -> Vec<Vec<u8>> {
    let mut seeds = format_fixtures(".bgeo");
    seeds.extend(format_fixtures(".bgeo.gz"));
    seeds
}

fn xyz_seeds() -> Vec<Vec<u8>> {
    format_fixtures(".xyz")
}

/// A tetrahedron written in `formats`, with and without normals and attributes.
fn mesh_seeds(formats: &[MeshFormat]) -> Vec<Vec<u8>> {
    let vertices = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
    let normals = vertices
        .iter()
        .map(|v| (*v - Vec3::splat(0.25)).normalize())
        .collect();
    let triangles = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let full = TriMesh {
        vertices,
        normals,
        triangles,
    };
    let bare = TriMesh {
        normals: Vec::new(),
        ..full.clone()
    };
    let named = [
        (
            "density".to_string(),
            Attribute::Scalar(vec![1000.0, 999.5, 1001.0, 1000.25]),
        ),
        (
            "velocity".to_string(),
            Attribute::Vector(full.vertices.clone()),
        ),
    ];
    let mut seeds = Vec::new();
    for &format in formats {
        for (mesh, named) in [(&full, &named[..]), (&bare, &[][..])] {
            let named = if format.holds_attributes() {
                named
            } else {
                &[]
            };
            let with = VertexAttributes {
                velocities: None,
                named,
            };
            let mut bytes = Vec::new();
            write_mesh_with(mesh, &with, format, &mut bytes).unwrap();
            seeds.push(bytes);
        }
    }
    seeds
}

fn obj_mesh_seeds() -> Vec<Vec<u8>> {
    mesh_seeds(&[MeshFormat::Obj])
}

fn ply_mesh_seeds() -> Vec<Vec<u8>> {
    mesh_seeds(&[MeshFormat::PlyBinary, MeshFormat::PlyAscii])
}

fn vtk_mesh_seeds() -> Vec<Vec<u8>> {
    mesh_seeds(&[MeshFormat::Vtk])
}

fn vtu_mesh_seeds() -> Vec<Vec<u8>> {
    mesh_seeds(&[MeshFormat::Vtu])
}

fn vtp_mesh_seeds() -> Vec<Vec<u8>> {
    mesh_seeds(&[MeshFormat::Vtp])
}

fn raw_seeds() -> Vec<Vec<u8>> {
    let points: Vec<u8> = fixture_rows(5)
        .iter()
        .flat_map(|r| r[..3].iter().flat_map(|v| v.to_le_bytes()))
        .collect();
    let mut inf = points.clone();
    inf[32..36].copy_from_slice(&f32::NEG_INFINITY.to_le_bytes());
    vec![
        points.clone(),
        points[..12].to_vec(),
        Vec::new(),
        points[..25].to_vec(),
        inf,
    ]
}

// ---------------------------------------------------------------------------------------------
// Configuration text, lengths and sizes.

fn config_seeds() -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs");
    let mut files: Vec<PathBuf> = fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| Some(e.ok()?.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    let mut seeds: Vec<Vec<u8>> = files.iter().map(|p| fs::read(p).unwrap()).collect();
    seeds.push(Config::default().to_toml().into_bytes());
    for text in [
        "spacing = 0.014\ncell = \"r/4\"\nmax_memory = \"8G\"\n",
        "cell = 0.5\nspacing = 0.014\n",
        "engine = \"slices\"\n[slices]\nblock = 0\n",
        "threads = 0\n",
        "[field]\nkind = \"anisotropic\"\n",
        "[output]\nformat = \"obj\"\nattributes = [\"velocity\"]\n",
        "[band]\nhalf_width = \"-2r\"\n",
        "spacing = nan\n",
    ] {
        seeds.push(text.as_bytes().to_vec());
    }
    seeds
}

#[test]
fn config_text() {
    if !selected("config") {
        return;
    }
    let mut seeds = config_seeds();
    // The corpus's files come first among the seeds, so each is checked as it is.
    seeds.splice(0..0, corpus("config").into_iter().map(|(_, bytes)| bytes));
    let seed = base_seed();
    let n = cases(100);
    let mut failures = Vec::new();
    for case in 0..n {
        let mut rng = Rng::new(seed, "config", case);
        let mut input = rng.pick(&seeds).clone();
        if case >= seeds.len() as u64 {
            for _ in 0..1 + rng.below(3) {
                mutate(&mut input, &seeds, &mut rng);
            }
        }
        let text = String::from_utf8_lossy(&input).into_owned();
        let name =
            format!("config case {case} (SPLASH_FUZZ_SEED={seed:#x} SPLASH_FUZZ_TARGET=config)");
        let (result, peak) = measured(&name, || Config::from_toml(&text));
        let why = match result {
            Err(panic) => Some(format!("panicked: {panic}")),
            // toml's tables take ~80 bytes per byte of a text of many short keys.
            Ok(_) if peak > 128 * text.len() + (1 << 20) => Some(format!("used {peak} bytes")),
            Ok(Err(e)) => {
                let message = e.to_string();
                // A located error shows the line around the key, under the message.
                (!matches!(e, Error::Config(_)) || message.chars().count() > 2 * MAX_MESSAGE)
                    .then(|| format!("error: {message}"))
            }
            // What is accepted writes out and reads back as itself.
            Ok(Ok(config)) => match Config::from_toml(&config.to_toml()) {
                Ok(back) if format!("{back:?}") == format!("{config:?}") => None,
                Ok(back) => Some(format!("reads back as {back:?}, not {config:?}")),
                Err(e) => Some(format!("its own TOML is refused: {e}")),
            },
        };
        if let Some(why) = why {
            let saved = save_failure("config", "toml", &input);
            failures.push(format!("{name}: {why}; input saved as {}", saved.display()));
        }
    }
    eprintln!("fuzz: config: {n} cases, {} failures", failures.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Random text for a length or size: pieces of what users write.
fn quantity_text(rng: &mut Rng) -> String {
    const PIECES: &[&str] = &[
        "r",
        "/",
        "2",
        "0.5",
        "4",
        "1e30",
        "1e-40",
        "-",
        "+",
        " ",
        "nan",
        "inf",
        "K",
        "M",
        "G",
        "T",
        "B",
        "iB",
        "b",
        ".",
        "e",
        "9",
        "0",
        "18446744073709551616",
        "r/",
        "x",
        "µ",
        "\u{0}",
    ];
    let mut text: String = (0..1 + rng.below(5)).map(|_| *rng.pick(PIECES)).collect();
    if rng.below(20) == 0 {
        let at = rng.below(text.len() + 1);
        if text.is_char_boundary(at) {
            text.insert_str(at, &"9".repeat(1000));
        }
    }
    text
}

#[test]
fn lengths_and_sizes() {
    if !selected("quantities") {
        return;
    }
    let seed = base_seed();
    let n = cases(400);
    let mut failures = Vec::new();
    for case in 0..n {
        let mut rng = Rng::new(seed, "quantities", case);
        let text = quantity_text(&mut rng);
        let name = format!("quantities case {case} (SPLASH_FUZZ_SEED={seed:#x}): {text:?}");
        let (result, _) = measured(&name, || (Length::parse(&text), Bytes::parse(&text)));
        let why = match result {
            Err(panic) => Some(format!("panicked: {panic}")),
            Ok((length, bytes)) => {
                let mut why = None;
                match length {
                    // A length the parser accepts prints as text that parses back to it.
                    Ok(l) => match Length::parse(&l.to_string()) {
                        Ok(back)
                            if back.value().to_bits() == l.value().to_bits()
                                || back.value().is_nan() && l.value().is_nan() => {}
                        back => {
                            why = Some(format!(
                                "Length {l:?} prints as '{l}', which parses as {back:?}"
                            ))
                        }
                    },
                    Err(e) if e.to_string().chars().count() > MAX_MESSAGE => {
                        why = Some(e.to_string())
                    }
                    Err(_) => {}
                }
                match bytes {
                    Ok(b) if Bytes::parse(&b.to_string()).ok() != Some(b) => {
                        why = Some(format!(
                            "Bytes {b:?} prints as '{b}', which does not parse back"
                        ));
                    }
                    Err(e) if e.to_string().chars().count() > MAX_MESSAGE => {
                        why = Some(e.to_string())
                    }
                    _ => {}
                }
                why
            }
        };
        if let Some(why) = why {
            failures.push(format!("{name}: {why}"));
        }
    }
    eprintln!("fuzz: quantities: {n} cases, {} failures", failures.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

// ---------------------------------------------------------------------------------------------
// Reconstruction of tiny random particle sets.

/// A few dozen particles: a jittered cluster, some coincident, sometimes far from the origin
/// or spread far apart.
fn particles(rng: &mut Rng, r: f32) -> Vec<Vec3> {
    let n = 1 + rng.below(48);
    let offset = match rng.below(6) {
        0 => Vec3::splat(1e4 * r),
        1 => Vec3::new(-3e5, 2e5, 7e4) * r,
        _ => Vec3::ZERO,
    };
    let extent = *rng.pick(&[0.0, 0.5, 2.0, 4.0, 8.0, 40.0]) * r;
    let mut out: Vec<Vec3> = (0..n)
        .map(|_| offset + Vec3::new(rng.unit(), rng.unit(), rng.unit()) * extent)
        .collect();
    for _ in 0..rng.below(n) {
        let p = *rng.pick(&out);
        out.push(p);
    }
    out
}

#[test]
fn reconstruction() {
    if !selected("reconstruction") {
        return;
    }
    let seed = base_seed();
    let n = cases(5);
    let mut failures = Vec::new();
    // The reconstruction runs on this thread, so that its heap is counted with the case's.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .use_current_thread()
        .build()
        .unwrap();
    let max_memory = 64 << 20;
    for case in 0..n {
        let mut rng = Rng::new(seed, "reconstruction", case);
        let r = 10f32.powf(rng.unit() * 4.0 - 3.0);
        let positions = particles(&mut rng, r);
        let cell = *rng.pick(&["r/4", "r/2", "r", "2r", "4r", "0.3r"]);
        let config = Config {
            spacing: Some(r),
            cell: Length::parse(cell).unwrap(),
            engine: *rng.pick(&Engine::ALL),
            max_memory: Some(Bytes(max_memory)),
            ..Config::default()
        };
        let name = format!(
            "reconstruction case {case} (SPLASH_FUZZ_SEED={seed:#x} SPLASH_FUZZ_TARGET=reconstruction): \
             {} particles, r = {r}, cell {cell}, {:?}",
            positions.len(),
            config.engine
        );
        let run = || {
            pool.install(|| {
                let reconstructor = Reconstructor::new(config.clone())?;
                reconstructor.reconstruct(&positions)
            })
        };
        let (result, peak) = measured(&name, run);
        let why = match result {
            Err(panic) => Some(format!("panicked: {panic}")),
            Ok(_) if peak > 4 * max_memory as usize => Some(format!("used {peak} bytes of heap")),
            Ok(Ok(result)) => {
                let mesh = &result.mesh;
                let vertices = mesh.vertices.len();
                if mesh.vertices.iter().any(|v| !v.is_finite()) {
                    Some("a non-finite vertex".into())
                } else if mesh
                    .triangles
                    .iter()
                    .flatten()
                    .any(|&i| i as usize >= vertices)
                {
                    Some("a triangle refers to a vertex that is not there".into())
                } else {
                    let (again, _) = measured(&name, run);
                    match again {
                        Ok(Ok(again)) if again.mesh.triangles == mesh.triangles => None,
                        _ => Some("a second run gave another result".into()),
                    }
                }
            }
            Ok(Err(e)) => {
                let message = e.to_string();
                (!matches!(e, Error::Limit(_) | Error::Input(_) | Error::Config(_))
                    || message.chars().count() > MAX_MESSAGE)
                    .then(|| format!("error: {e:?}"))
            }
        };
        if let Some(why) = why {
            failures.push(format!("{name}: {why}"));
        }
    }
    eprintln!(
        "fuzz: reconstruction: {n} cases, {} failures",
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
