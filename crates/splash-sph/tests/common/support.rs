//! Particle sets the tests build, the real frames and fixtures they read, and scratch
//! directories: the helpers of the library's unit and integration tests, which the command
//! line's tests include as well. Names neither crate, so it compiles inside both.

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

use glam::Vec3;

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
