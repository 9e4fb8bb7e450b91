//! One particle frame as every reader returns it: positions, and per-particle attributes by
//! name.

use std::collections::BTreeMap;

use glam::Vec3;

/// One particle frame: positions, and per-particle attributes by name.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Particles {
    /// One position per particle.
    pub positions: Vec<Vec3>,
    /// One value per particle each, by name (`velocity`, `density`, …).
    pub attributes: BTreeMap<String, Attribute>,
}

/// The values of one per-particle attribute.
#[derive(Debug, Clone, PartialEq)]
pub enum Attribute {
    /// One number per particle (`density`, `pressure`, …).
    Scalar(Vec<f32>),
    /// One vector per particle (`velocity`, `normal`, …).
    Vector(Vec<Vec3>),
}

impl Particles {
    /// Particles in the frame.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether the frame has no particles.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Drops the particles outside the box `[min x, min y, min z, max x, max y, max z]`
    /// (bounds included; a non-finite position is outside), and their attribute values;
    /// returns how many were dropped.
    pub fn retain_in_box(&mut self, aabb: [f32; 6]) -> usize {
        let (lo, hi) = (Vec3::from_slice(&aabb[..3]), Vec3::from_slice(&aabb[3..]));
        let keep: Vec<bool> = self
            .positions
            .iter()
            .map(|p| p.cmpge(lo).all() && p.cmple(hi).all())
            .collect();
        let dropped = keep.iter().filter(|&&k| !k).count();
        if dropped == 0 {
            return 0;
        }
        fn retain<T>(values: &mut Vec<T>, keep: &[bool]) {
            let mut k = keep.iter();
            values.retain(|_| *k.next().unwrap_or(&false));
        }
        retain(&mut self.positions, &keep);
        for a in self.attributes.values_mut() {
            match a {
                Attribute::Scalar(s) => retain(s, &keep),
                Attribute::Vector(v) => retain(v, &keep),
            }
        }
        dropped
    }
}
