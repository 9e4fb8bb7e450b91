//! The tunable numbers of a reconstruction, with the paper defaults, as read from a TOML file.
//!
//! Lengths are given in units of the particle spacing `r` (Akinci et al. 2012 Sec. 3: cell sizes
//! 2r, r, r/2; support 4r; band 2r) and resolved to world lengths once `r` is known.

use std::fmt;
use std::path::Path;

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::field::FieldConfig;

/// Everything that decides the mesh of a frame; `splash recon` fills it from defaults, the
/// `--config` file and command-line flags, in that order of precedence (last wins).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Config {
    /// Particle spacing r in world units; estimated from the first frame when absent.
    pub spacing: Option<f32>,
    /// Marching Cubes cell edge length.
    pub cell: Length,
    pub surface_particles: SurfaceParticles,
    pub band: BandConfig,
    /// Where the mesh's vertex normals come from.
    pub normals: Normals,
    /// The Marching Slices engine's blocks.
    pub slices: SlicesConfig,
    /// The scalar field and its parameters (SSP07 by default).
    pub field: FieldConfig,
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BandConfig {
    pub half_width: Length,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            spacing: None,
            cell: Length::Spacings(0.5),
            surface_particles: SurfaceParticles::default(),
            band: BandConfig::default(),
            normals: Normals::default(),
            slices: SlicesConfig::default(),
            field: FieldConfig::default(),
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

impl Default for BandConfig {
    fn default() -> Self {
        BandConfig {
            half_width: Length::Spacings(2.0),
        }
    }
}

impl Config {
    pub fn from_file(path: &Path) -> Result<Config> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read the config file", path.display()))?;
        let config: Config =
            toml::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        config
            .validate()
            .with_context(|| format!("{}: invalid configuration", path.display()))?;
        Ok(config)
    }

    /// Checks the ranges that the TOML types cannot express.
    pub fn validate(&self) -> Result<()> {
        if let Some(r) = self.spacing {
            positive("spacing", r)?;
        }
        positive("cell", self.cell.value())?;
        positive(
            "surface_particles.support",
            self.surface_particles.support.value(),
        )?;
        if self.surface_particles.colour_threshold.is_nan()
            || self.surface_particles.colour_threshold < 0.0
        {
            bail!("surface_particles.colour_threshold must be ≥ 0");
        }
        if self.band.half_width.value().is_nan() || self.band.half_width.value() < 0.0 {
            bail!("band.half_width must be ≥ 0");
        }
        if !(1..=4096).contains(&self.slices.block) {
            bail!(
                "slices.block must be from 1 to 4096 cubes, got {}",
                self.slices.block
            );
        }
        self.field.validate()?;
        Ok(())
    }
}

fn positive(key: &str, v: f32) -> Result<()> {
    if !(v.is_finite() && v > 0.0) {
        bail!("{key} must be a positive length, got {v}");
    }
    Ok(())
}

/// A length either in multiples of the particle spacing r ("2r", "r", "r/2", "0.5r") or in
/// world units (a plain number).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Length {
    Spacings(f32),
    World(f32),
}

impl Length {
    pub fn resolve(self, r: f32) -> f32 {
        match self {
            Length::Spacings(k) => k * r,
            Length::World(l) => l,
        }
    }

    /// Errors unless the length is positive and finite, naming `key`.
    pub fn check_positive(self, key: &str) -> Result<()> {
        positive(key, self.value())
    }

    fn value(self) -> f32 {
        match self {
            Length::Spacings(v) | Length::World(v) => v,
        }
    }

    pub fn parse(text: &str) -> Result<Length> {
        let t = text.trim();
        let bad =
            || anyhow::anyhow!("'{text}' is not a length: use e.g. 2r, r, r/2, 0.5r or 0.007");
        if let Some(head) = t.strip_suffix("r/2") {
            let k = if head.is_empty() {
                1.0
            } else {
                head.parse::<f32>().map_err(|_| bad())?
            };
            return Ok(Length::Spacings(k / 2.0));
        }
        if let Some(head) = t.strip_suffix('r') {
            let k = if head.is_empty() {
                1.0
            } else {
                head.parse::<f32>().map_err(|_| bad())?
            };
            return Ok(Length::Spacings(k));
        }
        t.parse::<f32>().map(Length::World).map_err(|_| bad())
    }
}

impl fmt::Display for Length {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Length::Spacings(1.0) => write!(f, "r"),
            Length::Spacings(0.5) => write!(f, "r/2"),
            Length::Spacings(k) => write!(f, "{k}r"),
            Length::World(l) => write!(f, "{l}"),
        }
    }
}

impl Serialize for Length {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match *self {
            Length::World(l) => s.serialize_f32(l),
            Length::Spacings(_) => s.serialize_str(&self.to_string()),
        }
    }
}

impl<'de> Deserialize<'de> for Length {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Number(f64),
            Text(String),
        }
        match Raw::deserialize(d)? {
            Raw::Number(v) => Ok(Length::World(v as f32)),
            Raw::Text(t) => Length::parse(&t).map_err(serde::de::Error::custom),
        }
    }
}

/// World-unit parameters of one reconstruction, resolved from a [`Config`] and the spacing r.
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    pub spacing: f32,
    pub cell: f32,
    pub colour_support: f32,
    pub colour_threshold: f32,
    pub min_neighbours: u32,
    /// Band half-width after widening for large cells (see [`Params::resolve`]).
    pub band_half_width: f32,
    pub field: FieldConfig,
    pub normals: Normals,
    /// Cubes per side of a Marching Slices block.
    pub block: u32,
    /// The field's support radius in world units.
    pub support: f32,
}

impl Params {
    /// The band is widened to r + cell when that exceeds the configured half-width: the fields'
    /// surfaces lie within about r of the particles (SSP07: f ≤ 1 in eq. 1 with r̄ = r), and
    /// every corner of a cell that the surface crosses lies within one cell of it on each axis.
    /// At cells r and r/2 the paper's 2r already covers this; at 2r the band becomes 3r.
    /// Wherever the surface still leaves the band, the band closure follows it.
    pub fn resolve(config: &Config, r: f32) -> Params {
        let cell = config.cell.resolve(r);
        Params {
            spacing: r,
            cell,
            colour_support: config.surface_particles.support.resolve(r),
            colour_threshold: config.surface_particles.colour_threshold,
            min_neighbours: config.surface_particles.min_neighbours,
            band_half_width: config.band.half_width.resolve(r).max(r + cell),
            support: config.field.build(r).support(),
            field: config.field.clone(),
            normals: config.normals,
            block: config.slices.block,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_parse() {
        assert_eq!(Length::parse("2r").unwrap(), Length::Spacings(2.0));
        assert_eq!(Length::parse("r").unwrap(), Length::Spacings(1.0));
        assert_eq!(Length::parse("r/2").unwrap(), Length::Spacings(0.5));
        assert_eq!(Length::parse("0.25r").unwrap(), Length::Spacings(0.25));
        assert_eq!(Length::parse("0.007").unwrap(), Length::World(0.007));
        assert!(Length::parse("half").is_err());
    }

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
    fn unknown_keys_and_bad_ranges_are_errors() {
        assert!(toml::from_str::<Config>("cel = \"r\"").is_err());
        let c: Config = toml::from_str("[field]\nkind = \"ssp07\"\nt_low = 4.0").unwrap();
        assert!(c.validate().is_err());
        let c: Config = toml::from_str("cell = \"r/2\"\n[band]\nhalf_width = \"3r\"").unwrap();
        assert_eq!(c.cell, Length::Spacings(0.5));
        assert_eq!(c.band.half_width, Length::Spacings(3.0));
    }
}
