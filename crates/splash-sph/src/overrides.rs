//! Values put on top of a configuration: the command line's flags over `--config`, the Python
//! keyword arguments over `config=`, through this one rule.

use crate::bytes::Bytes;
use crate::config::{Config, Engine, Normals};
use crate::data::{MeshFormat, UpAxis};
use crate::error::Result;
use crate::field::FieldConfig;
use crate::length::Length;

/// Settings that replace a configuration's; None (or an empty `attributes`) keeps its value.
/// The callers parse them, so that their errors name the flag or argument.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// A field kind (`ssp07`, …): a different kind than the configuration's gets its defaults,
    /// the same kind keeps the parameters the configuration gives it.
    pub field: Option<String>,
    /// `spacing`: the particle spacing r.
    pub spacing: Option<f32>,
    /// `cell`: the Marching Cubes cell.
    pub cell: Option<Length>,
    /// `normals`.
    pub normals: Option<Normals>,
    /// `correct`: Newton steps of the correction.
    pub correct: Option<u32>,
    /// `slices.block`.
    pub block: Option<u32>,
    /// `engine`.
    pub engine: Option<Engine>,
    /// `threads` (at least 1).
    pub threads: Option<usize>,
    /// `max_memory`.
    pub max_memory: Option<Bytes>,
    /// `output.format`.
    pub format: Option<MeshFormat>,
    /// `output.up_axis`.
    pub up_axis: Option<UpAxis>,
    /// `output.attributes`.
    pub attributes: Option<Vec<String>>,
    /// `particle_aabb`.
    pub particle_aabb: Option<[f32; 6]>,
    /// `post.raw`: the field's exact isosurface, without post-processing.
    pub raw: Option<bool>,
    /// `post.mesh_aabb`.
    pub mesh_aabb: Option<[f32; 6]>,
    /// `post.min_component`, in particle volumes r³.
    pub min_component: Option<f64>,
    /// `post.decimate`.
    pub decimate: Option<Length>,
    /// `post.temporal`: surfaces that follow the fluid from frame to frame in a sequence.
    pub temporal: Option<bool>,
}

impl Config {
    /// The configuration with `overrides` on top, validated.
    pub fn apply(mut self, o: &Overrides) -> Result<Config> {
        if let Some(kind) = &o.field
            && self.field.kind() != kind
        {
            self.field = FieldConfig::named(kind)?;
        }
        self.spacing = o.spacing.or(self.spacing);
        self.cell = o.cell.unwrap_or(self.cell);
        self.normals = o.normals.unwrap_or(self.normals);
        self.correct = o.correct.unwrap_or(self.correct);
        self.slices.block = o.block.unwrap_or(self.slices.block);
        self.engine = o.engine.unwrap_or(self.engine);
        self.threads = o.threads.or(self.threads);
        self.max_memory = o.max_memory.or(self.max_memory);
        self.output.format = o.format.or(self.output.format);
        self.output.up_axis = o.up_axis.or(self.output.up_axis);
        if let Some(a) = &o.attributes {
            self.output.attributes = a.clone();
        }
        self.particle_aabb = o.particle_aabb.or(self.particle_aabb);
        self.post.raw = o.raw.unwrap_or(self.post.raw);
        self.post.mesh_aabb = o.mesh_aabb.or(self.post.mesh_aabb);
        self.post.min_component = o.min_component.or(self.post.min_component);
        self.post.decimate = o.decimate.or(self.post.decimate);
        self.post.temporal = o.temporal.unwrap_or(self.post.temporal);
        self.validate()?;
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_replace_only_what_they_give_and_a_field_of_the_same_kind_keeps_its_keys() {
        let config = Config::from_toml(
            "spacing = 0.02\nthreads = 3\n[field]\nkind = \"blobby\"\nblobbiness = 3.0\n",
        )
        .unwrap();
        assert_eq!(config.clone().apply(&Overrides::default()).unwrap(), config);
        let same_kind = Overrides {
            field: Some("blobby".into()),
            spacing: Some(0.05),
            ..Overrides::default()
        };
        let c = config.clone().apply(&same_kind).unwrap();
        assert_eq!((c.spacing, c.threads), (Some(0.05), Some(3)));
        assert_eq!(c.field, config.field);
        let other = Overrides {
            field: Some("metaball".into()),
            ..Overrides::default()
        };
        let c = config.clone().apply(&other).unwrap();
        assert_eq!(c.field, FieldConfig::named("metaball").unwrap());
        let zero = Overrides {
            threads: Some(0),
            ..Overrides::default()
        };
        assert!(config.apply(&zero).is_err());
    }
}
