//! `splash preview --report`: one JSON object for a run (hierarchy, image size, spacing,
//! workers) with a record per image written, the figures of the paper's Tables 1 and 3.

use std::io::Write;
use std::path::Path;

use serde_json::{Value, json};

use super::{BvhKind, PreviewStats};
use crate::error::Result;
use crate::frames::path_frame_number;
use crate::io::atomic::write_file;

/// One image written.
#[derive(Debug, Clone, Copy)]
pub struct ImageRecord<'a> {
    /// The particle file.
    pub input: &'a Path,
    /// The PNG written.
    pub output: &'a Path,
    /// The preview's figures.
    pub stats: &'a PreviewStats,
    /// The seconds the frame took: reading, building, rendering and writing.
    pub seconds: f64,
}

impl ImageRecord<'_> {
    fn json(&self) -> Value {
        let s = self.stats;
        let rays = s.rays.rays.max(1) as f64;
        json!({
            "frame": path_frame_number(self.input),
            "input": self.input.display().to_string(),
            "output": self.output.display().to_string(),
            "particles": s.particles,
            "build_ms": s.build.as_secs_f64() * 1e3,
            "render_ms": s.render.as_secs_f64() * 1e3,
            "rays": s.rays.rays,
            "rays_per_second": s.rays_per_second(),
            "camera_rays": s.camera_rays,
            "hits": s.hits,
            "nodes": s.bvh.nodes,
            "leaves": s.bvh.leaves,
            "metaballs_per_leaf": s.bvh.per_leaf(),
            "bvh_bytes": s.bvh.bytes,
            "traversals_per_ray": s.rays.nodes as f64 / rays,
            "intersection_tests_per_ray": s.rays.leaves as f64 / rays,
            "metaballs_per_ray": s.rays.metaballs as f64 / rays,
            "seconds": self.seconds,
        })
    }
}

/// Writes the report of a run that rendered `images` with hierarchy `bvh` at `size` pixels
/// (`spacing`: the particle spacing used) to `path` as JSON, whole or not at all. The
/// workers are the caller's pool's.
pub fn write_report<'a>(
    path: &Path,
    images: impl IntoIterator<Item = ImageRecord<'a>>,
    bvh: BvhKind,
    size: [u32; 2],
    spacing: Option<f32>,
) -> Result<()> {
    let frames: Vec<Value> = images.into_iter().map(|i| i.json()).collect();
    let report = json!({
        "bvh": bvh.name(),
        "size": size,
        "spacing": spacing,
        "threads": rayon::current_num_threads(),
        "frames": frames,
    });
    write_file(path, |file| {
        let text = serde_json::to_string_pretty(&report).map_err(std::io::Error::other)?;
        writeln!(file, "{text}")
    })
}
