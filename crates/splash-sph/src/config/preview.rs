//! `[preview]`: how `splash preview` shades its ray-traced images (samples, ambient occlusion,
//! colouring by a particle attribute); the surface itself is the `[field]` table's metaballs.

use serde::{Deserialize, Serialize};

use crate::error::Result;

/// Most samples per pixel and ambient-occlusion rays per pixel a preview accepts.
pub const MAX_SAMPLES: u32 = 256;

/// How a split is chosen (the ablation of Sec. 5.1.1's cost).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SplitRule {
    /// Binned SAH with the cost of splash's leaf test as measured: n + 16·k for n entries of
    /// which k (about 3) lie within R of the ray.
    #[default]
    Measured,
    /// Binned SAH with the paper's metaball cost n² (its leaf test sums n metaballs at each of
    /// about n samples).
    N2,
    /// The classic SAH, cost linear in the entries.
    Sah,
    /// The middle bin of the centres' extent on the longest axis, until 96 (`MEDIAN_LEAF`) entries.
    Median,
}

/// `[preview]` of a configuration (`splash preview`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PreviewConfig {
    /// Rays per pixel, stratified (a jittered k×k grid when a square, else N-rooks), averaged.
    pub samples: u32,
    /// Ambient-occlusion rays per pixel (spread over its samples); 0 turns it off.
    pub ao: u32,
    /// Colours the surface by this particle attribute (|v| for a vector) through viridis.
    pub color_by: Option<String>,
    /// Draws the colour scale with its minimum and maximum when colouring by an attribute.
    pub legend: bool,
    /// Ablations of the Fitted BVH (Gourmel et al. Tables 4–5); none changes the image.
    /// Fit each child's box to its metaballs' spheres (Sec. 5.1.2).
    pub fit: bool,
    /// Bound those spheres by r_max(n) rather than the cut-off R (Sec. 5.3.1).
    pub tight_boxes: bool,
    /// Discard split metaballs that cannot touch a leaf's surface (Sec. 5.3.2).
    pub discard: bool,
    /// The split cost: measured (splash's leaf test), n2 (the paper's), sah (linear) or
    /// median.
    pub split: SplitRule,
}

impl Default for PreviewConfig {
    fn default() -> Self {
        PreviewConfig {
            samples: 1,
            ao: 0,
            color_by: None,
            legend: true,
            fit: true,
            tight_boxes: true,
            discard: true,
            split: SplitRule::Measured,
        }
    }
}

impl PreviewConfig {
    /// Checks the ranges the TOML types cannot express, naming the key.
    pub fn validate(&self) -> Result<()> {
        if !(1..=MAX_SAMPLES).contains(&self.samples) {
            bail_config!(
                "preview.samples must be from 1 to {MAX_SAMPLES}, got {}",
                self.samples
            );
        }
        if self.ao > MAX_SAMPLES {
            bail_config!(
                "preview.ao must be from 0 (off) to {MAX_SAMPLES} rays, got {}",
                self.ao
            );
        }
        if self
            .color_by
            .as_deref()
            .is_some_and(|a| a.trim().is_empty())
        {
            bail_config!("preview.color_by is empty: name a particle attribute, e.g. velocity");
        }
        Ok(())
    }
}
