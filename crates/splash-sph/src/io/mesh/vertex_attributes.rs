//! The per-vertex attributes a mesh writer carries (PLY properties, VTK point data): a velocity
//! per vertex and further named columns.

use glam::Vec3;

use crate::data::Attribute;

/// Per-vertex data written beside the mesh, where the format has room for it (PLY, VTK; OBJ
/// and POV-Ray files refuse it).
///
/// In PLY, the vector `velocity` is written as the properties `vx vy vz`, any other vector
/// `name` as `name_x name_y name_z`, a scalar as a property of its name (all `float`). VTK
/// files get point data arrays of the attributes' names (vectors with 3 components).
#[derive(Clone, Copy, Debug, Default)]
pub struct VertexAttributes<'a> {
    /// One velocity per vertex, written as the attribute `velocity` (before `named`).
    pub velocities: Option<&'a [Vec3]>,
    /// Further attributes by name, one value per vertex each.
    pub named: &'a [(String, Attribute)],
}

/// A borrowed attribute column.
#[derive(Clone, Copy, Debug)]
pub(crate) enum AttributeValues<'a> {
    Scalar(&'a [f32]),
    Vector(&'a [Vec3]),
}

impl AttributeValues<'_> {
    pub(super) fn len(&self) -> usize {
        match self {
            Self::Scalar(s) => s.len(),
            Self::Vector(v) => v.len(),
        }
    }
}

impl<'a> VertexAttributes<'a> {
    /// Whether there is nothing to write.
    pub fn is_empty(&self) -> bool {
        self.velocities.is_none() && self.named.is_empty()
    }

    /// Every attribute by name, `velocity` first.
    pub(crate) fn arrays(&self) -> Vec<(&'a str, AttributeValues<'a>)> {
        let velocities = self
            .velocities
            .map(|v| ("velocity", AttributeValues::Vector(v)));
        velocities
            .into_iter()
            .chain(self.named.iter().map(|(name, a)| {
                let values = match a {
                    Attribute::Scalar(s) => AttributeValues::Scalar(s),
                    Attribute::Vector(v) => AttributeValues::Vector(v),
                };
                (name.as_str(), values)
            }))
            .collect()
    }
}
