//! Ray-traced previews of the metaball surface straight from the particles, without a mesh:
//! the Fitted BVH of Gourmel et al. 2010 (*Fitted BVH for Fast Raytracing of Metaballs*).
//!
//! The surface is the zero set of the `metaball` field (the configuration's `[field]` table
//! when it is of that kind, else the metaball defaults), the one `splash recon --field
//! metaball` meshes. [`Previewer::render`] builds the hierarchy (a Fitted BVH, or the plain
//! BVH of [`BvhKind`]), traces stratified samples per pixel through a [`Camera`], shades hits
//! with a key light from the camera's side, a fill and a sky ambient, a hard shadow and
//! optional ambient occlusion ([`Style`]), coloured by a particle attribute through viridis
//! with a legend ([`Colouring`]) or plain; rows in parallel, every random number a hash of
//! pixel and sample, so the image does not depend on the number of threads.
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
mod colormap;
mod fitted_bvh;
mod legend;
mod metaballs;
mod png_file;
mod report;
mod sampling;
mod shade;
mod trace;

#[cfg(test)]
mod tests;

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;
use rayon::prelude::*;

use crate::bytes::default_limit;
use crate::config::{self, Config};
use crate::error::Result;
use crate::field::{FieldConfig, MetaballConfig};
use crate::io::Attribute;

pub use crate::config::preview::PreviewConfig;
pub use camera::{Camera, parse_size, robust_bounds, up_vector};
pub(crate) use colormap::viridis_srgb;
pub(crate) use fitted_bvh::FittedBvh;
pub use fitted_bvh::{BvhKind, BvhOptions, BvhStats, SplitRule};
pub(crate) use metaballs::Metaballs;
pub use png_file::{Image, write_png};
pub use report::{ImageRecord, write_report};
pub use shade::{Style, parse_colour};
pub use trace::RayCounts;
pub(crate) use trace::Tracer;

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
    /// Camera rays (samples).
    pub camera_rays: u64,
    /// Counts over all rays, camera, shadow and ambient occlusion.
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
pub(crate) fn metaball_config(config: &Config) -> MetaballConfig {
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
    options: BvhOptions,
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
            options: BvhOptions {
                fit: config.preview.fit,
                tight: config.preview.tight_boxes,
                discard: config.preview.discard,
                split: config.preview.split,
            },
            max_memory: config.max_memory.map_or_else(default_limit, |b| b.0),
            pool,
        })
    }

    /// The same previewer with another hierarchy (`--bvh plain` to compare).
    pub fn with_bvh(mut self, kind: BvhKind) -> Previewer {
        self.kind = kind;
        self
    }

    /// The same previewer with the Fitted BVH's parts switched as `options` says.
    pub fn with_options(mut self, options: BvhOptions) -> Previewer {
        self.options = options;
        self
    }

    /// The field drawn.
    #[cfg(test)]
    pub(crate) fn field(&self) -> Metaballs {
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
    #[cfg(test)]
    pub(crate) fn build(&self, positions: &[Vec3]) -> Result<FittedBvh> {
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
        self.install(|| {
            FittedBvh::build_with(positions, self.field, self.kind, self.options, budget)
        })
    }

    /// Builds the hierarchy and renders the image of `camera`.
    pub fn render(&self, positions: &[Vec3], camera: &Camera, style: &Style) -> Result<Preview> {
        self.render_coloured(positions, None, camera, style)
    }

    /// [`render`](Self::render), the surface coloured by `colouring` when given (one value per
    /// position) with its legend when `style.legend`.
    pub fn render_coloured(
        &self,
        positions: &[Vec3],
        colouring: Option<&Colouring>,
        camera: &Camera,
        style: &Style,
    ) -> Result<Preview> {
        if let Some(c) = colouring
            && c.values.len() != positions.len()
        {
            bail_input!(
                "{} particles but {} values to colour them by",
                positions.len(),
                c.values.len()
            );
        }
        if !(1..=config::preview::MAX_SAMPLES).contains(&style.samples)
            || style.ao > config::preview::MAX_SAMPLES
        {
            bail_config!(
                "{} samples and {} ambient-occlusion rays per pixel: samples must be from 1 to \
                 {max}, ao from 0 to {max}",
                style.samples,
                style.ao,
                max = config::preview::MAX_SAMPLES
            );
        }
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
        let (mut image, rays, hits) = self.install(|| render_image(&bvh, camera, style, colouring));
        if let Some(c) = colouring
            && style.legend
        {
            legend::draw(&mut image, c.min, c.max);
        }
        Ok(Preview {
            image,
            stats: PreviewStats {
                particles: positions.len(),
                build,
                render: start.elapsed(),
                bvh: bvh.stats(),
                hits,
                camera_rays: camera.width as u64 * camera.height as u64 * style.samples as u64,
                rays,
            },
        })
    }
}

/// Per-particle values that colour the surface, and the range viridis spans.
#[derive(Debug, Clone)]
pub struct Colouring {
    /// One value per particle, in the particles' order.
    pub values: Vec<f32>,
    /// The value drawn dark purple.
    pub min: f32,
    /// The value drawn yellow.
    pub max: f32,
}

impl Colouring {
    /// `attribute`'s values (a vector's magnitude), spanning their minimum to maximum.
    pub fn new(attribute: &Attribute) -> Colouring {
        let values: Vec<f32> = match attribute {
            Attribute::Scalar(s) => s.clone(),
            Attribute::Vector(v) => v.iter().map(|v| v.length()).collect(),
        };
        let finite = values.iter().copied().filter(|v| v.is_finite());
        let min = finite.clone().fold(f32::INFINITY, f32::min);
        let max = finite.fold(f32::NEG_INFINITY, f32::max);
        let (min, max) = if min <= max { (min, max) } else { (0.0, 0.0) };
        Colouring { values, min, max }
    }

    /// The colouring by attribute `name` of frame `input` (found through the usual spellings,
    /// `v` for velocity, or its x, y, z components), or an error naming the file and listing
    /// the attributes it has.
    pub fn from_frame(
        input: &Path,
        attributes: &mut BTreeMap<String, Attribute>,
        name: &str,
    ) -> Result<Colouring> {
        match crate::attribute_names::take(attributes, name) {
            Some(a) => Ok(Colouring::new(&a)),
            None => {
                let has: Vec<&str> = attributes.keys().map(String::as_str).collect();
                bail_input!(
                    "'{}' has no particle attribute '{name}' to colour by; it has {}",
                    input.display(),
                    if has.is_empty() {
                        "none".to_string()
                    } else {
                        has.join(", ")
                    }
                )
            }
        }
    }

    /// Where `v` falls in the range, 0 to 1 (0 for an empty range).
    fn position(&self, v: f32) -> f32 {
        if self.max > self.min {
            (v - self.min) / (self.max - self.min)
        } else {
            0.0
        }
    }
}

/// Traces and shades every pixel of `camera`'s image, rows in parallel: each pixel depends on
/// nothing but its rays, whose samples are hashes of pixel and sample number, and the counts
/// are integer sums, so any thread count gives the same.
pub(crate) fn render_image(
    bvh: &FittedBvh,
    camera: &Camera,
    style: &Style,
    colouring: Option<&Colouring>,
) -> (Image, RayCounts, u64) {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let tracer = match colouring {
        Some(c) => Tracer::new(bvh).with_values(&c.values),
        None => Tracer::new(bvh),
    };
    let (right, up) = camera.basis();
    let lights = shade::Lights::new(camera.forward(), right, up);
    let colour = shade::to_linear(style.colour);
    let background = shade::to_linear(style.background);
    let offset = bvh.field().cutoff * 0.02;
    // Occluders within a few metaball radii darken; farther ones are the scene, not the crease.
    let ao_reach = 4.0 * bvh.field().cutoff;
    let n = style.samples.max(1);
    let ao_rays = style.ao.div_ceil(n);
    let mut rgb = vec![0u8; w * h * 3];
    let (counts, hits) = rgb
        .par_chunks_mut(w * 3)
        .enumerate()
        .map(|(y, row)| {
            let mut scratch = trace::Scratch::default();
            let mut counts = RayCounts::default();
            let mut hits = 0u64;
            let (mut dirs, mut found) = (Vec::new(), Vec::new());
            let y = y as u32;
            let o = camera.position;
            for (x, px) in row.chunks_exact_mut(3).enumerate() {
                let x = x as u32;
                let mut sum = Vec3::ZERO;
                dirs.clear();
                dirs.extend((0..n).map(|s| {
                    let (fx, fy) = sampling::pixel_offset(x, y, s, n);
                    camera.direction_at(x as f32 + fx, y as f32 + fy)
                }));
                // The pixel's samples traverse together.
                tracer.first_hits(o, &dirs, &mut found, &mut scratch, &mut counts);
                for (s, (&d, &hit)) in (0..n).zip(dirs.iter().zip(&found)) {
                    let Some(hit) = hit else {
                        sum += background;
                        continue;
                    };
                    hits += 1;
                    let p = o + hit.t * d;
                    let facing = if hit.normal.dot(d) > 0.0 {
                        -hit.normal
                    } else {
                        hit.normal
                    };
                    let start = p + offset * facing;
                    let shadowed = style.shadows
                        && facing.dot(lights.key) > 0.0
                        && tracer.occluded(
                            start,
                            lights.key,
                            0.0,
                            f32::INFINITY,
                            &mut scratch,
                            &mut counts,
                        );
                    let mut blocked = 0;
                    for j in 0..ao_rays {
                        let k = s * ao_rays + j;
                        let (u1, u2) =
                            (sampling::uniform(x, y, k, 2), sampling::uniform(x, y, k, 3));
                        let dir = sampling::cosine_direction(facing, u1, u2);
                        if tracer.occluded(start, dir, 0.0, ao_reach, &mut scratch, &mut counts) {
                            blocked += 1;
                        }
                    }
                    let open = 1.0 - blocked as f32 / ao_rays.max(1) as f32;
                    let albedo = match colouring {
                        Some(c) => shade::to_linear(viridis_srgb(c.position(hit.value))),
                        None => colour,
                    };
                    sum += shade::shade(hit.normal, d, &lights, shadowed, open, albedo);
                }
                px.copy_from_slice(&shade::to_srgb(sum / n as f32));
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
