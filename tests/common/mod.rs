//! Particle sets the tests build, and the real frames they read.
#![allow(dead_code)]

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Output;
use std::sync::atomic::{AtomicU32, Ordering};

use glam::{IVec3, Vec3};
use rustc_hash::FxHashMap;
use splash_sph::TriMesh;

/// Particles on a cubic lattice of spacing `r` inside a ball.
pub fn lattice_ball(center: Vec3, radius: f32, r: f32) -> Vec<Vec3> {
    let n = (radius / r).ceil() as i32;
    let mut out = Vec::new();
    for z in -n..=n {
        for y in -n..=n {
            for x in -n..=n {
                let p = Vec3::new(x as f32, y as f32, z as f32) * r;
                if p.length() <= radius {
                    out.push(center + p);
                }
            }
        }
    }
    out
}

/// The repository's top directory, whichever crate's tests include this file.
pub fn repository() -> PathBuf {
    let mut dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    while !dir.join("fixtures").is_dir() {
        assert!(
            dir.pop(),
            "no fixtures/ above {}",
            env!("CARGO_MANIFEST_DIR")
        );
    }
    dir
}

/// A file in `../shared/data`, or None (with a notice) where that folder is absent.
pub fn shared_data(relative: &str) -> Option<PathBuf> {
    let path = repository().join("../shared/data").join(relative);
    if path.exists() {
        Some(path)
    } else {
        eprintln!(
            "skipped: {} is absent (CI and the team have ../shared; a fresh clone does not)",
            path.display()
        );
        None
    }
}

pub fn fixture(name: &str) -> PathBuf {
    repository().join("fixtures").join(name)
}

/// A fresh directory under the system temp dir, removed when dropped.
pub struct TempDir(pub PathBuf);

impl TempDir {
    pub fn new(name: &str) -> Self {
        static NEXT: AtomicU32 = AtomicU32::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("splash-test-{}-{n}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    /// Writes `name` (creating parent directories) and returns its path.
    pub fn file(&self, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let path = self.path(name);
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        fs::write(&path, contents).unwrap();
        path
    }

    /// `name/` as `-o` takes a directory.
    pub fn out_dir(&self, name: &str) -> String {
        format!("{}/", self.path(name).display())
    }

    pub fn entries(&self) -> Vec<String> {
        entries(&self.0)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

/// Sorted names in `dir`, hidden ones included; none if it does not exist.
pub fn entries(dir: &Path) -> Vec<String> {
    let Ok(read) = fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut names: Vec<String> = read
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Reproducible uniform numbers in [−½, ½) from a linear congruential generator.
pub struct Jitter(u32);

impl Jitter {
    pub fn new(seed: u32) -> Jitter {
        Jitter(seed)
    }

    pub fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (self.0 >> 8) as f32 / (1u32 << 24) as f32 - 0.5
    }

    pub fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
}

/// Whether two meshes are the same up to float rounding: same vertex and triangle counts, each
/// vertex of `a` within `tol` of a vertex of `b`, and the same triangles under that matching
/// (up to rotation). The scatter engine sums each vertex's particle contributions in another
/// order than the gather (particle by particle rather than lane-wise over a gathered list), and
/// with offsets rounded from world rather than brick-local coordinates, so its field values
/// differ from the gather's in the last bits, and so do the interpolated vertices. The narrow
/// band and the full gather share the gather code and match exactly (`tol` 0).
///
/// Vertices closer than `tol` to each other (a surface through a grid vertex puts the vertices
/// of several edges there) form one group; a group must have as many vertices in both meshes,
/// and triangles are compared as triples of groups.
pub fn same_mesh(a: &TriMesh, b: &TriMesh, tol: f32) -> Result<(), String> {
    if a.vertices.len() != b.vertices.len() || a.triangles.len() != b.triangles.len() {
        return Err(format!(
            "{} vertices and {} triangles vs {} and {}",
            a.vertices.len(),
            a.triangles.len(),
            b.vertices.len(),
            b.triangles.len()
        ));
    }
    // Buckets of side `2 tol` (at least 1e-4, far below the cells): a match lies in one of the
    // 27 around.
    let side = (2.0 * tol).max(1e-4);
    let key = |v: Vec3| (v / side).floor().as_ivec3();
    let mut buckets: FxHashMap<IVec3, Vec<u32>> = FxHashMap::default();
    for (i, &v) in b.vertices.iter().enumerate() {
        buckets.entry(key(v)).or_default().push(i as u32);
    }
    // The lowest index of the vertices of `b` within `tol` of `v`.
    let group = |v: Vec3| {
        let k = key(v);
        let mut best: Option<u32> = None;
        for d in (0..27).map(|n| IVec3::new(n % 3 - 1, n / 3 % 3 - 1, n / 9 - 1)) {
            for &j in buckets.get(&(k + d)).into_iter().flatten() {
                if (b.vertices[j as usize] - v).abs().max_element() <= tol {
                    best = Some(best.map_or(j, |m| m.min(j)));
                }
            }
        }
        best
    };
    let mut count: FxHashMap<u32, i64> = FxHashMap::default();
    let mut ga = Vec::with_capacity(a.vertices.len());
    for &v in &a.vertices {
        let g = group(v).ok_or_else(|| format!("vertex {v} has no match within {tol}"))?;
        *count.entry(g).or_default() += 1;
        ga.push(g);
    }
    let gb: Vec<u32> = b.vertices.iter().map(|&v| group(v).unwrap()).collect();
    for &g in &gb {
        *count.entry(g).or_default() -= 1;
    }
    if let Some((g, n)) = count.iter().find(|(_, n)| **n != 0) {
        return Err(format!(
            "{n} more vertices near {} in the first mesh",
            b.vertices[*g as usize]
        ));
    }
    let canonical = |t: [u32; 3]| {
        let first = (0..3).min_by_key(|&i| t[i]).unwrap();
        [t[first], t[(first + 1) % 3], t[(first + 2) % 3]]
    };
    let triples = |tris: &[[u32; 3]], g: &[u32]| {
        let mut out: Vec<[u32; 3]> = tris
            .iter()
            .map(|t| canonical(t.map(|i| g[i as usize])))
            .collect();
        out.sort_unstable();
        out
    };
    let (ta, tb) = (triples(&a.triangles, &ga), triples(&b.triangles, &gb));
    match ta.iter().zip(&tb).position(|(x, y)| x != y) {
        None => Ok(()),
        Some(k) => Err(format!("triangles differ: {:?} vs {:?}", ta[k], tb[k])),
    }
}

/// Distance, in cells, from each vertex of `a` to the nearest vertex of `b`.
pub fn offsets(a: &TriMesh, b: &TriMesh, cell: f32) -> Vec<f32> {
    let key = |v: Vec3| (v / cell).floor().as_ivec3();
    let mut buckets: FxHashMap<IVec3, Vec<Vec3>> = FxHashMap::default();
    for &v in &b.vertices {
        buckets.entry(key(v)).or_default().push(v);
    }
    a.vertices
        .iter()
        .map(|&v| {
            (0..27)
                .map(|n| IVec3::new(n % 3 - 1, n / 3 % 3 - 1, n / 9 - 1))
                .flat_map(|d| buckets.get(&(key(v) + d)).into_iter().flatten())
                .map(|w| (*w - v).abs().max_element() / cell)
                .fold(f32::INFINITY, f32::min)
        })
        .collect()
}

/// Reads `path`, which must fail within a second (a huge allocation or a scan of a declared
/// count would take far longer) with a message naming the file and holding every `expected`.
pub fn assert_read_fails(
    path: &Path,
    format: Option<splash_sph::io::InputFormat>,
    expected: &[&str],
) {
    let start = std::time::Instant::now();
    let result = splash_sph::read_particles(path, format);
    let elapsed = start.elapsed();
    let message = match result {
        Ok(points) => panic!("{} read {} particles", path.display(), points.len()),
        Err(e) => e.to_string(),
    };
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(message.contains(&*name), "no file name in: {message}");
    for want in expected {
        assert!(message.contains(want), "no '{want}' in: {message}");
    }
    assert!(
        elapsed < std::time::Duration::from_secs(1),
        "{message}: took {elapsed:?}"
    );
}

/// A finished run of the `splash` binary.
pub struct Run {
    pub command: String,
    pub success: bool,
    pub stderr: String,
}

impl Run {
    pub fn ok(self) -> Self {
        assert!(self.success, "{} failed:\n{}", self.command, self.stderr);
        self
    }

    pub fn failed(self) -> Self {
        assert!(
            !self.success,
            "{} succeeded:\n{}",
            self.command, self.stderr
        );
        self
    }

    pub fn has(self, text: &str) -> Self {
        assert!(
            self.stderr.contains(text),
            "{}: no '{text}' in:\n{}",
            self.command,
            self.stderr
        );
        self
    }

    /// The JSON log lines of one event kind (every line must be an object; serde_json writes
    /// them, so they are well-formed).
    pub fn events(&self, kind: &str) -> Vec<Event> {
        let tag = format!("{{\"event\":\"{kind}\"");
        self.stderr
            .lines()
            .inspect(|l| assert!(l.starts_with('{') && l.ends_with('}'), "not JSON: {l}"))
            .filter(|l| l.starts_with(&tag))
            .map(|l| Event(l.to_owned()))
            .collect()
    }

    /// Frame numbers of the `frame` events, in log order.
    pub fn frames(&self) -> Vec<u64> {
        self.events("frame")
            .iter()
            .map(|e| e.get("frame").parse().unwrap())
            .collect()
    }
}

/// One JSON log line. Parsing it with serde_json would add 15-20 s to this test's build on two
/// cores; splash writes flat objects whose top-level fields are found by name.
pub struct Event(pub String);

impl Event {
    /// The raw JSON text of top-level field `key`: `12`, `"3/4"`, `[…]`.
    pub fn get(&self, key: &str) -> &str {
        let text = &self.0;
        let start = text
            .find(&format!("\"{key}\":"))
            .unwrap_or_else(|| panic!("no {key} in {text}"))
            + key.len()
            + 3;
        let (mut depth, mut quoted, mut escaped) = (0, false, false);
        for (i, c) in text[start..].char_indices() {
            if std::mem::take(&mut escaped) {
                continue;
            }
            match c {
                '\\' if quoted => escaped = true,
                '"' => quoted = !quoted,
                '[' | '{' if !quoted => depth += 1,
                ']' | '}' if !quoted && depth > 0 => depth -= 1,
                ',' | '}' if !quoted && depth == 0 => return &text[start..start + i],
                _ => {}
            }
        }
        panic!("unterminated {key} in {text}")
    }
}

/// The run of `command` that gave `output`; it must not have panicked.
pub fn finish(command: String, output: Output) -> Run {
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(
        output.status.code().is_some() && !stderr.contains("panicked"),
        "{command}: {}\n{stderr}",
        output.status
    );
    Run {
        command,
        success: output.status.success(),
        stderr,
    }
}
