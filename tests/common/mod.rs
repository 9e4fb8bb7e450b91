//! Particle sets the tests build, and the real frames they read.
#![allow(dead_code)]

use std::path::PathBuf;

use glam::Vec3;
use splash::config::{Config, Length, Params};

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

pub fn params(r: f32, cell: &str) -> Params {
    let config = Config {
        cell: Length::parse(cell).unwrap(),
        ..Config::default()
    };
    Params::resolve(&config, r)
}

/// A file in `../shared/data`, or None (with a notice) where that folder is absent.
pub fn shared_data(relative: &str) -> Option<PathBuf> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data")
        .join(relative);
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
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}
