//! `splash bench temporal --rigid-step`: one frame translated rigidly, a fixed step a frame, as
//! a sequence. Its field moves exactly with its particles, so whatever jitter a mesher shows on
//! it comes from the grid the surface moves across (Marching Cubes' cut of the same surface at
//! another phase), not from the fluid.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use splash_sph::temporal::FrameMotion;
use splash_sph::{Vec3, read_particles};

/// A step in cells per frame: "X,Y,Z".
pub fn parse_step(text: &str) -> Result<Vec3> {
    let parts: Vec<f32> = text
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--rigid-step '{text}' must be three numbers X,Y,Z (cells)"))?;
    match parts[..] {
        [x, y, z] if parts.iter().all(|v| v.is_finite()) => Ok(Vec3::new(x, y, z)),
        _ => bail!("--rigid-step '{text}' must be three finite numbers X,Y,Z (cells)"),
    }
}

/// Writes `count` frames into `dir`: frame k is `first`'s particles moved by k × `step`, in
/// world units, with their ids (the file's own, else their order) so that the measure matches
/// them exactly. Binary PLY, `x y z id`, which splash and the peer both read.
pub fn write_frames(first: &Path, step: Vec3, count: usize, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut particles = read_particles(first, None)?;
    let (motion, _) = FrameMotion::new(particles.positions, &mut particles.attributes);
    let ids = motion
        .ids
        .unwrap_or_else(|| (0..motion.positions.len() as u32).collect());
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create '{}'", dir.display()))?;
    (0..count)
        .map(|k| {
            let path = dir.join(format!("frame_{k:04}.ply"));
            let shift = step * k as f32;
            let mut bytes = format!(
                "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\n\
                 property float y\nproperty float z\nproperty int id\nend_header\n",
                ids.len()
            )
            .into_bytes();
            bytes.reserve(16 * ids.len());
            for (p, id) in motion.positions.iter().zip(&ids) {
                for c in (*p + shift).to_array() {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
                bytes.extend_from_slice(&id.to_le_bytes());
            }
            std::fs::File::create(&path)
                .and_then(|mut f| f.write_all(&bytes))
                .with_context(|| format!("cannot write '{}'", path.display()))?;
            Ok(path)
        })
        .collect()
}
