//! The tunable numbers of a reconstruction, with the paper defaults, as read from a TOML file.
//!
//! Lengths are given in units of the particle spacing `r` (Akinci et al. 2012 Sec. 3: cell sizes
//! 2r, r, r/2; support 4r; band 2r) and resolved to world lengths once `r` is known.

mod errors;
pub(crate) mod iso;
pub(crate) mod preview;

use std::fmt;
use std::path::Path;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::bytes::{Bytes, default_limit};
use crate::data::{MeshFormat, UpAxis};
use crate::error::{Error, Result};
use crate::field::{FieldConfig, ScalarField, Scattering};
use crate::length::{Length, positive};

/// Everything that decides a run: the mesh of a frame, the engine and its resources, and how
/// the mesh is written. `splash recon` fills it from these defaults, the `--config` file and
/// command-line flags, in that order of precedence (last wins); `splash config show` prints it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Config {
    /// Particle spacing r in world units. A [`Reconstructor`](crate::Reconstructor) needs it; a
    /// [`Batch`](crate::pipeline::Batch) without it estimates it from the first frame
    /// ([`estimate_spacing`](crate::estimate_spacing)).
    pub spacing: Option<f32>,
    /// Marching Cubes cell edge length; at most 4r ([`validate`](Self::validate) refuses
    /// larger cells once the spacing is known).
    pub cell: Length,
    /// Which engine reconstructs (all give the same mesh but for small blobs far from every
    /// surface particle at small cells, which the narrow band can miss).
    pub engine: Engine,
    /// Worker threads; all cores when absent. The mesh does not depend on it.
    pub threads: Option<usize>,
    /// Heap a frame may plan to use (`"8G"`, `"512M"`, or bytes); when absent 80 % of the
    /// smallest of the cgroup limit, SLURM's memory and the available memory (8 GiB where none
    /// is known).
    pub max_memory: Option<Bytes>,
    /// Which particles are on the surface.
    pub surface_particles: SurfaceParticles,
    /// How far the band of sampled vertices reaches around them.
    pub band: BandConfig,
    /// Where the mesh's vertex normals come from; a post-processed mesh gets area-weighted
    /// normals of its smoothed surface unless this is `none`.
    pub normals: Normals,
    /// Newton steps that move each vertex along its cube edge onto the field's exact
    /// isosurface (Marching Correctors, Sec. III-D2; the paper uses a few); 0, the default,
    /// keeps Marching Cubes' linear interpolation.
    pub correct: u32,
    /// The Marching Slices engine's blocks.
    pub slices: SlicesConfig,
    /// The scalar field and its parameters (SSP07 by default).
    pub field: FieldConfig,
    /// How meshes are written.
    pub output: OutputConfig,
    /// Isosurfaces of particle quantities (`splash iso`, Marching Correctors).
    pub iso: iso::IsoConfig,
    /// How previews are shaded (`splash preview`).
    pub preview: preview::PreviewConfig,
    /// `[min x, min y, min z, max x, max y, max z]`: particles outside this box (bounds
    /// included in it) are dropped before the reconstruction, with their attributes. All are
    /// kept when absent.
    pub particle_aabb: Option<[f32; 6]>,
    /// What happens to the mesh after the engine (smoothing, volume); `post.raw` keeps the
    /// field's exact isosurface.
    pub post: crate::mesh::post::PostConfig,
}

/// A baseline of Fig. 7 of Rosenberg & Birdwell 2008 (approach 1 is the slices engine).
// Hidden with `Reconstructor::with_baseline`, for `splash bench slices` only.
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Baseline {
    /// Approach 2: surface-following Marching Cubes in blocks, each with its corners in 3D
    /// arrays and its particles in a voxel grid of cells R_c.
    BlockedCubes,
    /// Approach 3: surface-following Marching Cubes with hash maps for the corners and the
    /// particles' voxel grid, unbounded.
    HashedCubes,
}

/// Which grid vertices get a field value, and in what order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Engine {
    /// Only the band around the surface particles (Akinci et al. 2012 Sec. 4.1).
    #[default]
    NarrowBand,
    /// Every vertex of the particles' bounding box widened by the support: the paper's
    /// "Z-index" gather without a narrow band. Memory follows the volume.
    FullGather,
    /// Serial scatter of every particle into per-vertex sums over the same full grid, then all
    /// cells triangulated: the paper's "scatter" row (SSP07 only).
    Scatter,
    /// Block-parallel Marching Slices (Rosenberg & Birdwell 2008).
    Slices,
}

impl Engine {
    /// Every engine, in the order of the paper's tables.
    pub const ALL: [Engine; 4] = [
        Engine::NarrowBand,
        Engine::FullGather,
        Engine::Scatter,
        Engine::Slices,
    ];

    /// The engine's name in configs and on the command line (`narrow-band`, …).
    pub fn name(self) -> &'static str {
        match self {
            Engine::NarrowBand => "narrow-band",
            Engine::FullGather => "full-gather",
            Engine::Scatter => "scatter",
            Engine::Slices => "slices",
        }
    }

    /// The engine of a [`name`](Self::name).
    pub fn parse(text: &str) -> Result<Engine> {
        match Engine::ALL.into_iter().find(|e| e.name() == text.trim()) {
            Some(e) => Ok(e),
            None => bail_config!(
                "unknown engine '{text}': use narrow-band, full-gather, scatter or slices"
            ),
        }
    }

    /// Whether the engine processes every vertex of the grid (and is subject to the memory
    /// limit before it starts).
    pub fn is_full_grid(self) -> bool {
        matches!(self, Engine::FullGather | Engine::Scatter)
    }
}

/// `[output]`: how meshes are written.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputConfig {
    /// Mesh format; from the output file's extension when absent, else OBJ.
    pub format: Option<MeshFormat>,
    /// Rotates the mesh on output so that this axis is up; coordinates as they are when absent.
    pub up_axis: Option<UpAxis>,
    /// Per-vertex attributes interpolated from the particles and written (PLY, VTK, VTU,
    /// VTP, USD): any particle attribute by name, in the canonical spelling of
    /// [`attribute_names`](crate::attribute_names) (`velocity` for `v`, `vel`, `vx vy vz`).
    /// USD output takes `velocity` whenever the particles have it, listed here or not.
    pub attributes: Vec<String>,
}

/// What is wrong with an attribute name that no mesh file could hold.
fn attribute_name_problem(name: &str) -> Option<String> {
    if name.is_empty() || name.chars().any(|c| c.is_whitespace() || c.is_control()) {
        return Some(format!(
            "the attribute name '{name}' is empty or holds spaces"
        ));
    }
    if name
        .chars()
        .any(|c| matches!(c, '"' | '<' | '>' | '&' | ','))
    {
        return Some(format!(
            "the attribute name '{name}' holds one of \" < > & , (VTK XML names cannot)"
        ));
    }
    None
}

/// Parses `--particle-aabb MINX,MINY,MINZ,MAXX,MAXY,MAXZ`.
pub(crate) fn parse_aabb(text: &str) -> Result<[f32; 6]> {
    let values: Vec<&str> = text.split(',').map(str::trim).collect();
    let mut out = [0.0f32; 6];
    if values.len() != 6 {
        bail_config!(
            "expected six numbers MINX,MINY,MINZ,MAXX,MAXY,MAXZ, got {}",
            values.len()
        );
    }
    for (o, v) in out.iter_mut().zip(&values) {
        *o = match v.parse::<f32>() {
            Ok(x) => x,
            Err(_) => bail_config!("'{v}' is not a number"),
        };
    }
    if !(0..3).all(|i| out[i].is_finite() && out[i + 3].is_finite() && out[i] <= out[i + 3]) {
        bail_config!("each minimum must be finite and at most its maximum: {text}");
    }
    Ok(out)
}

impl OutputConfig {
    /// Whether the velocities are asked for.
    pub fn velocities(&self) -> bool {
        self.attributes.iter().any(|a| a == "velocity")
    }

    /// Parses a comma-separated list as a user writes it: names of particle attributes, each
    /// turned into its canonical spelling (`v`, `vel`, `velocities` → `velocity`), once each.
    pub fn parse_attributes(text: &str) -> Result<Vec<String>> {
        let mut out: Vec<String> = Vec::new();
        for name in text.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            let name = crate::attribute_names::canonical(name);
            if let Some(problem) = attribute_name_problem(name) {
                bail_config!("{problem}");
            }
            if !out.iter().any(|n| n == name) {
                out.push(name.to_string());
            }
        }
        Ok(out)
    }
}

/// `[slices]`: the block-parallel Marching Slices engine (`--engine slices`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SlicesConfig {
    /// Cubes per side of a block (Rosenberg & Birdwell 2008, Sec. 3), without its margin.
    pub block: u32,
}

impl Default for SlicesConfig {
    fn default() -> Self {
        SlicesConfig { block: 64 }
    }
}

/// `normals = "field" | "grid" | "none"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Normals {
    /// The field's analytic gradient at each vertex: exact, and costs a gather per vertex
    /// (about a third of the field's sampling time at cell r/2).
    #[default]
    Field,
    /// Central differences of the sampled grid values, interpolated along the edge: almost
    /// free, smoothed over a cell.
    Grid,
    /// No normals in the output (the renderer computes its own).
    None,
}

impl Normals {
    /// `field`, `grid` or `none`.
    pub fn parse(text: &str) -> Result<Normals> {
        match text.trim().to_ascii_lowercase().as_str() {
            "field" => Ok(Normals::Field),
            "grid" => Ok(Normals::Grid),
            "none" => Ok(Normals::None),
            _ => bail_config!("unknown normals '{text}': expected field, grid or none"),
        }
    }
}

/// Surface particle detection (Sec. 4): colour field of Müller et al. 2003 plus a neighbour count.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SurfaceParticles {
    /// Support radius h of the colour field kernel and of the neighbour count.
    pub support: Length,
    /// A particle is on the surface when |∇c|·h exceeds this (dimensionless).
    pub colour_threshold: f32,
    /// Particles with fewer neighbours than this within `support` are splashes, hence surface.
    pub min_neighbours: u32,
}

/// The narrow band (Sec. 4.1): grid vertices in the box of this half-width around a surface
/// particle are surface vertices.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BandConfig {
    /// Half-width of the box around each surface particle; `None`: the field's own
    /// ([`FieldConfig::band_half_width`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub half_width: Option<Length>,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            spacing: None,
            cell: Length::Spacings(0.5),
            surface_particles: SurfaceParticles::default(),
            band: BandConfig::default(),
            normals: Normals::default(),
            correct: 0,
            slices: SlicesConfig::default(),
            field: FieldConfig::default(),
            engine: Engine::default(),
            threads: None,
            max_memory: None,
            output: OutputConfig::default(),
            iso: iso::IsoConfig::default(),
            preview: preview::PreviewConfig::default(),
            particle_aabb: None,
            post: crate::mesh::post::PostConfig::default(),
        }
    }
}

impl Default for SurfaceParticles {
    fn default() -> Self {
        SurfaceParticles {
            support: Length::Spacings(2.0),
            colour_threshold: 0.4,
            min_neighbours: 25,
        }
    }
}

/// The smallest particle spacing a configuration takes: below it the field's r³ underflows f32
/// (a ball scaled by 10⁻²⁰ gave an empty mesh).
pub(crate) const MIN_SPACING: f32 = 1e-9;
/// The largest particle spacing a configuration takes: above it the field's powers of r overflow
/// f32 (`spacing = 1e30` gave an empty mesh).
pub(crate) const MAX_SPACING: f32 = 1e9;

impl Config {
    /// Reads and validates a TOML file; errors name the file (and the key).
    pub fn from_file(path: &Path) -> Result<Config> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            message: format!("{}: cannot read the config file: {source}", path.display()),
            path: path.to_path_buf(),
            io_error: source,
        })?;
        Config::from_toml(&text).map_err(|e| e.context(path.display()))
    }

    /// Parses and validates TOML text; errors point at the offending key's line.
    pub fn from_toml(text: &str) -> Result<Config> {
        let config: Config = toml::from_str(text).map_err(|e| {
            let e = errors::parse_error(text, e);
            Error::config(errors::render_parse_error(text, &e))
        })?;
        config.validate().map_err(|e| match e {
            Error::Config(m) => Error::config(errors::validation_error(text, &m)),
            e => e.context("invalid configuration"),
        })?;
        Ok(config)
    }

    /// The configuration as TOML, every key written.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a configuration is always representable in TOML")
    }

    /// The configuration with the defaults that depend on other keys written out (the band
    /// the field chooses), as `splash config show` prints it.
    pub fn effective(&self) -> Config {
        let mut c = self.clone();
        c.band.half_width = Some(self.band_half_width());
        c
    }

    /// `band.half_width`, or where it is not set the field's own; 2r with grid normals, which
    /// difference the values a vertex beyond each corner of the cells the surface crosses.
    pub fn band_half_width(&self) -> Length {
        match (self.band.half_width, self.normals) {
            (Some(w), _) => w,
            (None, Normals::Grid) => Length::Spacings(2.0),
            (None, _) => self.field.band_half_width(),
        }
    }

    /// Checks the ranges that the TOML types cannot express.
    pub fn validate(&self) -> Result<()> {
        if let Some(r) = self.spacing {
            positive("spacing", r)?;
            if !(MIN_SPACING..=MAX_SPACING).contains(&r) {
                bail_config!(
                    "spacing {} is outside {MIN_SPACING:e} to {MAX_SPACING:e}, where the field's \
                     powers of r (r³, 1/r³) stay within f32's range; scale the coordinates (to \
                     metres, say) and the spacing with them",
                    crate::error::figure(r)
                );
            }
        }
        positive("cell", self.cell.value())?;
        self.check_cell_against_spacing()?;
        self.post.validate()?;
        positive(
            "surface_particles.support",
            self.surface_particles.support.value(),
        )?;
        if self.surface_particles.colour_threshold.is_nan()
            || self.surface_particles.colour_threshold < 0.0
        {
            bail_config!("surface_particles.colour_threshold must be ≥ 0");
        }
        if let Some(w) = self.band.half_width
            && (w.value().is_nan() || w.value() < 0.0)
        {
            bail_config!("band.half_width must be ≥ 0");
        }
        if !(1..=4096).contains(&self.slices.block) {
            bail_config!(
                "slices.block must be from 1 to 4096 cubes, got {}",
                self.slices.block
            );
        }
        if self.correct > MAX_CORRECT {
            bail_config!(
                "correct must be from 0 to {MAX_CORRECT} Newton steps, got {}",
                self.correct
            );
        }
        if self.threads == Some(0) {
            bail_config!("threads must be at least 1");
        }
        for name in &self.output.attributes {
            if let Some(problem) = attribute_name_problem(name) {
                bail_config!("output.attributes: {problem}");
            }
        }
        if let Some(format) = self.output.format
            && !self.output.attributes.is_empty()
            && !format.holds_attributes()
        {
            bail_config!(
                "output.attributes needs PLY, VTK, VTU, VTP, USD or VDB output: .{} files have \
                 no place for vertex attributes",
                format.extension()
            );
        }
        if let Some(b) = &self.particle_aabb
            && !(0..3).all(|i| b[i].is_finite() && b[i + 3].is_finite() && b[i] <= b[i + 3])
        {
            bail_config!(
                "particle_aabb must be six finite numbers MINX, MINY, MINZ, MAXX, MAXY, MAXZ with \
                 each minimum at most its maximum"
            );
        }
        self.field.validate()?;
        self.iso.validate()?;
        self.preview.validate()?;
        Ok(())
    }

    /// Refuses cells above [`MAX_CELL`] spacings, once the spacing is known (a cell in units of
    /// r, at once). The mesh thins out as the cell grows: sheets and droplets thinner than a
    /// cell fall between grid vertices, then the whole fluid does (`fixtures/frame_0040.ply`,
    /// r = 0.014: 2336 triangles at 4r, 88 at 12r, none at 36r), and the run would end without
    /// a word. An error rather than a warning: the library has no channel for warnings, and a
    /// farm's logs are read after the frames are rendered.
    fn check_cell_against_spacing(&self) -> Result<()> {
        let (cell, spacings) = match (self.cell, self.spacing) {
            (Length::Spacings(k), _) => (self.cell.to_string(), k),
            (Length::World(l), Some(r)) => {
                let k = l / r;
                (format!("{} ({}r for r = {r})", short(l), short(k)), k)
            }
            (Length::World(_), None) => return Ok(()),
        };
        // The tolerance lets a world cell of exactly 4r through its f32 rounding.
        if spacings > MAX_CELL * (1.0 + 1e-5) {
            bail_config!(
                "cell {cell} is far larger than the particle spacing: above {MAX_CELL}r the mesh \
                 loses every feature thinner than a cell and then the fluid itself; use at most \
                 {MAX_CELL}r (the usual cells are 2r, r and r/2), or check the spacing"
            );
        }
        Ok(())
    }
}

/// The largest cell, in particle spacings, that [`Config::validate`] accepts: twice the
/// paper's coarsest cell (2r), and the reach of SSP07's kernel (4r).
const MAX_CELL: f32 = 4.0;

/// The most Newton steps `correct` takes: every step that falls back to bisection halves the
/// bracket, and 32 halvings leave less than f32 can tell apart along an edge.
const MAX_CORRECT: u32 = 32;

/// `x` to three decimals, or in exponent notation when very large or small (f32's
/// `Display` writes 1e30 with all its 31 digits).
fn short(x: f32) -> String {
    if (1e-3..1e5).contains(&x.abs()) {
        format!("{}", (x * 1000.0).round() / 1000.0)
    } else {
        format!("{x:.2e}")
    }
}

/// World-unit parameters of one reconstruction, resolved from a [`Config`] and the spacing r,
/// with the field built for that spacing (once: every engine samples this one).
#[derive(Clone)]
pub(crate) struct Params {
    pub spacing: f32,
    pub cell: f32,
    pub colour_support: f32,
    pub colour_threshold: f32,
    pub min_neighbours: u32,
    /// Band half-width after widening for large cells (see [`Params::resolve`]).
    pub band_half_width: f32,
    /// The scalar field in world units.
    pub field: Arc<dyn ScalarField>,
    /// Its kind, as configured (`ssp07`, …).
    pub field_kind: &'static str,
    pub normals: Normals,
    /// Newton steps of the vertex correction; 0 for none.
    pub correct: u32,
    /// Cubes per side of a Marching Slices block.
    pub block: u32,
    /// The field's support radius in world units (the field's own, kept for the gathers).
    pub support: f32,
    pub engine: Engine,
    /// A baseline of Fig. 7 of Rosenberg & Birdwell 2008 instead of the engine
    /// (`splash bench slices`).
    pub baseline: Option<Baseline>,
    /// Heap bytes a full-grid engine may plan to use.
    pub max_memory: u64,
}

impl fmt::Debug for Params {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Params")
            .field("spacing", &self.spacing)
            .field("cell", &self.cell)
            .field("field", &self.field_kind)
            .field("support", &self.support)
            .field("engine", &self.engine)
            .finish_non_exhaustive()
    }
}

impl Params {
    /// The field's form for the scatter engine, or an error for the fields that have none.
    pub fn scattering(&self) -> Result<&dyn Scattering> {
        match self.field.scattering() {
            Some(s) => Ok(s),
            None => bail_config!(
                "the scatter engine supports the ssp07 field only, not {}: use the narrow-band or full-gather engine",
                self.field_kind
            ),
        }
    }

    /// The band is widened to r + cell when that exceeds the configured half-width: the fields'
    /// surfaces lie within about r of the particles (SSP07: f ≤ 1 in eq. 1 with r̄ = r), and
    /// every corner of a cell that the surface crosses lies within one cell of it on each axis.
    /// At cells r and r/2 the paper's 2r already covers this; at 2r the band becomes 3r.
    /// Wherever the surface still leaves the band, the band closure follows it.
    pub fn resolve(config: &Config, r: f32) -> Params {
        let cell = config.cell.resolve(r);
        let field: Arc<dyn ScalarField> = config.field.build(r).into();
        Params {
            spacing: r,
            cell,
            colour_support: config.surface_particles.support.resolve(r),
            colour_threshold: config.surface_particles.colour_threshold,
            min_neighbours: config.surface_particles.min_neighbours,
            band_half_width: config.band_half_width().resolve(r).max(r + cell),
            support: field.support(),
            field,
            field_kind: config.field.kind(),
            normals: config.normals,
            correct: config.correct,
            block: config.slices.block,
            engine: config.engine,
            baseline: None,
            max_memory: config.max_memory.map_or_else(default_limit, |b| b.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_widens_only_for_large_cells() {
        let mut c = Config::default();
        for (cell, band) in [(0.5, 2.0), (1.0, 2.0), (2.0, 3.0)] {
            c.cell = Length::Spacings(cell);
            let p = Params::resolve(&c, 1.0);
            assert_eq!(p.band_half_width, band, "cell {cell}r");
        }
    }

    #[test]
    fn the_density_field_has_its_own_band_unless_one_is_set() {
        let mut c = Config {
            field: FieldConfig::named("density").unwrap(),
            ..Config::default()
        };
        for (cell, band) in [(0.5, 1.5), (1.0, 2.0), (2.0, 3.0)] {
            c.cell = Length::Spacings(cell);
            assert_eq!(
                Params::resolve(&c, 1.0).band_half_width,
                band,
                "cell {cell}r"
            );
        }
        c.cell = Length::Spacings(0.5);
        c.band.half_width = Some(Length::Spacings(2.0));
        assert_eq!(Params::resolve(&c, 1.0).band_half_width, 2.0);
        // What `config show` prints is the band that runs; what is read back is what was set.
        c.band.half_width = None;
        assert!(!c.to_toml().contains("half_width"));
        assert!(
            c.effective()
                .to_toml()
                .contains("[band]\nhalf_width = \"r\"")
        );
        c.normals = Normals::Grid;
        assert_eq!(Params::resolve(&c, 1.0).band_half_width, 2.0);
    }

    #[test]
    fn cells_far_larger_than_the_spacing_are_refused() {
        let config = |cell: &str, spacing: Option<f32>| Config {
            cell: Length::parse(cell).unwrap(),
            spacing,
            ..Config::default()
        };
        for (cell, spacing) in [("4r", None), ("0.056", Some(0.014)), ("0.5", None)] {
            assert!(config(cell, spacing).validate().is_ok(), "{cell}");
        }
        for (cell, spacing) in [("4.1r", None), ("0.5", Some(0.014)), ("1000", Some(1.0))] {
            let e = config(cell, spacing).validate().unwrap_err().to_string();
            assert!(e.starts_with("cell ") && e.contains("at most 4r"), "{e}");
        }
        let e = config("1e30", Some(0.014)).validate().unwrap_err();
        assert!(
            e.to_string()
                .starts_with("cell 1.00e30 (7.14e31r for r = 0.014)"),
            "{e}"
        );
        let e = config("0.5", Some(0.014)).validate().unwrap_err();
        assert!(
            e.to_string()
                .starts_with("cell 0.5 (35.714r for r = 0.014)"),
            "{e}"
        );
    }

    #[test]
    fn unknown_keys_and_bad_ranges_are_errors() {
        assert!(toml::from_str::<Config>("cel = \"r\"").is_err());
        let c: Config = toml::from_str("[field]\nkind = \"ssp07\"\nt_low = 4.0").unwrap();
        assert!(c.validate().is_err());
        let c: Config = toml::from_str("cell = \"r/2\"\n[band]\nhalf_width = \"3r\"").unwrap();
        assert_eq!(c.cell, Length::Spacings(0.5));
        assert_eq!(c.band.half_width, Some(Length::Spacings(3.0)));
    }
}
