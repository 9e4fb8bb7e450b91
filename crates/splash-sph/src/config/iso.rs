//! `[iso]`: the tunable numbers of Marching Correctors (Schindler et al., Sec. III–IV), with the
//! paper's defaults. The virtual grid's cell is the configuration's `cell` (r/2 ≈ 0.5h).

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::length::Length;

/// `[iso]` of a configuration (`splash iso`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IsoConfig {
    /// Compact support 2h of the cubic spline when the frame has no `h` column (the density
    /// field's 2r). With an `h` column each particle's support is 2h.
    pub support: Length,
    /// Multiplies every particle's support (Sec. IV-D: 1, 0.75, 0.5 for previews).
    pub kernel_scale: f32,
    /// Shepard-normalised interpolation Σ V A W / Σ V W; plain SPH Σ V A W when false (the paper).
    pub shepard: bool,
    /// Newton steps per vertex along its cube edge (Sec. III-D2); 0 is plain Marching Cubes.
    pub correct: u32,
    /// Cells with a corner whose sum of weights Σ V W is below this are discarded (Sec. III-D3).
    pub node_threshold: f32,
    /// Triangles are trimmed where the sum of weights at their vertices falls below this (Fig. 3).
    pub vertex_threshold: f32,
    /// Particle pairs closer than this fraction of their support pair up for seeds (Sec. III-C).
    /// The paper's h is half its kernels' extent (0.5), but its particles sit 0.55h apart; at
    /// the usual support 2r, h = r reaches only the nearest neighbours, and on
    /// `fixtures/frame_0040.ply` (density 1000, Shepard) seeds from pairs within h missed 4 of
    /// the full grid's 36 components. The whole support (1.0) missed none.
    pub seed_reach: f32,
    /// Slices of corner values kept in the cache (Sec. III-B).
    pub cache_slices: u32,
    /// Most virtual cells materialised (seed or visited) before a frame is refused.
    pub max_cells: u64,
}

impl Default for IsoConfig {
    fn default() -> Self {
        IsoConfig {
            support: Length::Spacings(2.0),
            kernel_scale: 1.0,
            shepard: false,
            correct: 3,
            node_threshold: 0.1,
            vertex_threshold: 0.5,
            seed_reach: 1.0,
            cache_slices: 3,
            max_cells: 200_000_000,
        }
    }
}

impl IsoConfig {
    /// Checks the ranges the TOML types cannot express, naming the key.
    pub fn validate(&self) -> Result<()> {
        self.support.check_positive("iso.support")?;
        if !(self.kernel_scale > 0.0 && self.kernel_scale.is_finite()) {
            bail_config!(
                "iso.kernel_scale must be positive, got {}",
                self.kernel_scale
            );
        }
        if !(0.0..1.0).contains(&self.node_threshold) {
            bail_config!(
                "iso.node_threshold must be in [0, 1), got {}",
                self.node_threshold
            );
        }
        if !(self.vertex_threshold >= self.node_threshold && self.vertex_threshold < 1.0) {
            bail_config!(
                "iso.vertex_threshold must be from node_threshold ({}) to below 1, got {}",
                self.node_threshold,
                self.vertex_threshold
            );
        }
        if !(self.seed_reach > 0.0 && self.seed_reach <= 1.0) {
            bail_config!("iso.seed_reach must be in (0, 1], got {}", self.seed_reach);
        }
        if !(2..=64).contains(&self.cache_slices) {
            bail_config!(
                "iso.cache_slices must be from 2 to 64, got {}",
                self.cache_slices
            );
        }
        if self.correct > 100 {
            bail_config!(
                "iso.correct must be at most 100 Newton steps, got {}",
                self.correct
            );
        }
        if self.max_cells == 0 {
            bail_config!("iso.max_cells must be at least 1");
        }
        Ok(())
    }
}
