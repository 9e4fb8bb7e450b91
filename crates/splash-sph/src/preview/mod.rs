//! Ray-traced previews of the metaball surface straight from the particles, without a mesh:
//! the Fitted BVH of Gourmel et al. 2010 (*Fitted BVH for Fast Raytracing of Metaballs*).
//!
//! The surface is the zero set of the `metaball` field (the configuration's `[field]` table
//! when it is of that kind, else the metaball defaults), the one `splash recon --field
//! metaball` meshes. [`Previewer::render`] builds the hierarchy ([`FittedBvh`]), traces one
//! ray per pixel through a [`Camera`] ([`Tracer`]), shades hits with Phong and a hard shadow
//! ([`Style`]), rows in parallel; the image does not depend on the number of threads.
//!
//! ```
//! use splash_sph::preview::{Camera, Previewer, Style};
//! use splash_sph::{Config, Vec3};
//!
//! let positions = vec![Vec3::ZERO];
//! let previewer = Previewer::new(&Config { spacing: Some(0.1), ..Config::default() })?;
//! let camera = Camera::look_at(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, Vec3::Y, 20.0, 64, 48)?;
//! let preview = previewer.render(&positions, &camera, &Style::default())?;
//! assert_eq!(preview.image.rgb.len(), 64 * 48 * 3);
//! # Ok::<(), splash_sph::Error>(())
//! ```

mod camera;
mod fitted_bvh;
mod metaballs;
mod png_file;
mod shade;
mod trace;

#[cfg(test)]
mod tests;

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;
use rayon::prelude::*;

use crate::bytes::default_limit;
use crate::config::Config;
use crate::error::Result;
use crate::field::{FieldConfig, MetaballConfig};

pub use camera::{Camera, parse_size, robust_bounds, up_vector};
pub use fitted_bvh::{Aabb, BvhKind, BvhStats, FittedBvh};
pub use metaballs::Metaballs;
pub use png_file::{Image, encode_png, write_png};
pub use shade::{Style, parse_colour};
pub use trace::{Hit, RayCounts, Scratch, Tracer};

/// One rendered frame and what it took.
pub struct Preview {
    /// The picture.
    pub image: Image,
    /// Times and counts.
    pub stats: PreviewStats,
}

/// Figures of one preview: the paper's Tables 1 and 3 in shape.
#[derive(Debug, Clone, Copy, Default)]
pub struct PreviewStats {
    /// Particles drawn.
    pub particles: usize,
    /// Hierarchy build time.
    pub build: Duration,
    /// Tracing and shading time.
    pub render: Duration,
    /// The hierarchy's counts.
    pub bvh: BvhStats,
    /// Camera rays that hit the fluid.
    pub hits: u64,
    /// Camera rays.
    pub camera_rays: u64,
    /// Counts over all rays, camera and shadow.
    pub rays: RayCounts,
}

impl PreviewStats {
    /// Rays (camera and shadow) per second of rendering.
    pub fn rays_per_second(&self) -> f64 {
        self.rays.rays as f64 / self.render.as_secs_f64().max(1e-9)
    }
}

/// The metaball parameters a configuration gives a preview: its `[field]` table when that is
/// a metaball field, else the metaball defaults (what `--field metaball` meshes).
pub fn metaball_config(config: &Config) -> MetaballConfig {
    match &config.field {
        FieldConfig::Metaball(m) => m.clone(),
        _ => MetaballConfig::default(),
    }
}

/// Renders previews with one configuration (spacing, metaball field, threads, memory limit).
#[derive(Clone)]
pub struct Previewer {
    field: Metaballs,
    kind: BvhKind,
    max_memory: u64,
    pool: Option<Arc<rayon::ThreadPool>>,
}

impl Previewer {
    /// A previewer for `config`, which must give the spacing; the hierarchy is a Fitted BVH.
    pub fn new(config: &Config) -> Result<Previewer> {
        let Some(r) = config.spacing else {
            bail_config!(
                "the particle spacing is not set: give it in the configuration (spacing = r), \
                 or estimate it once per sequence with estimate_spacing"
            );
        };
        crate::length::positive("spacing", r)?;
        let metaball = metaball_config(config);
        metaball.validate()?;
        let pool = crate::worker_pool::worker_pool(config.threads)?;
        Ok(Previewer {
            field: Metaballs::new(&metaball, r),
            kind: BvhKind::Fitted,
            max_memory: config.max_memory.map_or_else(default_limit, |b| b.0),
            pool,
        })
    }

    /// The same previewer with another hierarchy (`--bvh plain` to compare).
    pub fn with_bvh(mut self, kind: BvhKind) -> Previewer {
        self.kind = kind;
        self
    }

    /// The field drawn.
    pub fn field(&self) -> Metaballs {
        self.field
    }

    /// How far the surface reaches beyond the particles' centres at most (the lone
    /// metaball's radius): the margin of auto-framing.
    pub fn margin(&self) -> f32 {
        self.field.lone_radius()
    }

    fn install<T: Send>(&self, f: impl FnOnce() -> T + Send) -> T {
        match &self.pool {
            Some(pool) => pool.install(f),
            None => f(),
        }
    }

    /// Builds the hierarchy over `positions` (finite), within the memory limit.
    pub fn build(&self, positions: &[Vec3]) -> Result<FittedBvh> {
        self.build_within(positions, self.max_memory)
    }

    fn build_within(&self, positions: &[Vec3], budget: u64) -> Result<FittedBvh> {
        if let Some((i, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            bail_input!(
                "particle {i} has a non-finite position ({}, {}, {})",
                p.x,
                p.y,
                p.z
            );
        }
        self.install(|| FittedBvh::build(positions, self.field, self.kind, budget))
    }

    /// Builds the hierarchy and renders the image of `camera`.
    pub fn render(&self, positions: &[Vec3], camera: &Camera, style: &Style) -> Result<Preview> {
        camera::check_size(camera.width, camera.height)?;
        let image_bytes = camera.width as u64 * camera.height as u64 * 3;
        if image_bytes >= self.max_memory {
            bail_limit!(
                "a {}x{} image takes {} MB, more than the memory limit (max_memory)",
                camera.width,
                camera.height,
                image_bytes >> 20
            );
        }
        let start = Instant::now();
        let bvh = self.build_within(positions, self.max_memory - image_bytes)?;
        let build = start.elapsed();
        let start = Instant::now();
        let (image, rays, hits) = self.install(|| render_image(&bvh, camera, style));
        Ok(Preview {
            image,
            stats: PreviewStats {
                particles: positions.len(),
                build,
                render: start.elapsed(),
                bvh: bvh.stats(),
                hits,
                camera_rays: camera.width as u64 * camera.height as u64,
                rays,
            },
        })
    }
}

/// Traces and shades every pixel of `camera`'s image, rows in parallel: each pixel depends on
/// nothing but its ray, and the counts are integer sums, so any thread count gives the same.
pub fn render_image(bvh: &FittedBvh, camera: &Camera, style: &Style) -> (Image, RayCounts, u64) {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let tracer = Tracer::new(bvh);
    let (right, up) = camera.basis();
    let light = shade::light_direction(camera.forward(), right, up);
    let colour = shade::to_linear(style.colour);
    let offset = bvh.field().cutoff * 0.02;
    let mut rgb = vec![0u8; w * h * 3];
    let (counts, hits) = rgb
        .par_chunks_mut(w * 3)
        .enumerate()
        .map(|(y, row)| {
            let mut scratch = trace::Scratch::default();
            let mut counts = RayCounts::default();
            let mut hits = 0u64;
            for (x, px) in row.chunks_exact_mut(3).enumerate() {
                let d = camera.direction(x as u32, y as u32);
                let o = camera.position;
                let hit = tracer.first_hit(o, d, 0.0, f32::INFINITY, &mut scratch, &mut counts);
                let value = match hit {
                    None => style.background,
                    Some(hit) => {
                        hits += 1;
                        let p = o + hit.t * d;
                        let facing = if hit.normal.dot(d) > 0.0 {
                            -hit.normal
                        } else {
                            hit.normal
                        };
                        let shadowed = style.shadows
                            && facing.dot(light) > 0.0
                            && tracer.occluded(
                                p + offset * facing,
                                light,
                                0.0,
                                f32::INFINITY,
                                &mut scratch,
                                &mut counts,
                            );
                        shade::to_srgb(shade::phong(hit.normal, d, light, shadowed, colour))
                    }
                };
                px.copy_from_slice(&value);
            }
            (counts, hits)
        })
        .reduce(
            || (RayCounts::default(), 0),
            |(mut a, ha), (b, hb)| {
                a.add(&b);
                (a, ha + hb)
            },
        );
    let image = Image {
        width: camera.width,
        height: camera.height,
        rgb,
    };
    (image, counts, hits)
}
