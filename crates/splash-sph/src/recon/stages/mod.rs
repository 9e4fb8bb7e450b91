//! The stages of Algorithm 1 (Akinci et al. 2012) that every engine shares: surface particles
//! (and the smaller band of lone ones), the scalar field on the band (deferred where its sign
//! suffices), band closure, triangulation, normals, and the vertex correction.

pub(crate) mod band_closure;
pub(crate) mod deferred_values;
pub(crate) mod field_sampling;
pub(crate) mod flow_mean;
pub(crate) mod lone_particles;
pub(crate) mod normals;
pub(crate) mod side_field;
pub(crate) mod surface_particles;
pub(crate) mod triangulation;
pub(crate) mod vertex_correction;
