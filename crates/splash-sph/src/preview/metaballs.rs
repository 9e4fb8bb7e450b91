//! The metaball field of `[field] kind = "metaball"` as the ray tracer sees it: the same kernel,
//! cut-off and iso level as the mesher's (`field/metaball.rs`), written for rays.
//!
//! f(x) = T − c Σ_i t_i(x)^α with t_i = max(0, 1 − |x − p_i|²/R²): negative inside the fluid.
//! Along a ray x(t) = o + t·d (|d| = 1) a metaball whose centre projects to t_i at distance
//! δ_i from the ray adds c·(q_i − (t − t_i)²/R²)^α with q_i = 1 − δ_i²/R², a polynomial in t
//! wherever it is positive: the tracer collects (t_i, q_i) once per leaf and ray.

#[cfg(test)]
use glam::Vec3;

use crate::field::MetaballConfig;

/// The field's parameters in world units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metaballs {
    /// Cut-off radius R (the bounding spheres' radius).
    pub cutoff: f32,
    /// α.
    pub exponent: i32,
    /// T / c: a point is inside where Σ t_i^α reaches it.
    pub level: f32,
}

impl Metaballs {
    /// The field of `config` for particle spacing `r`, as the mesher resolves it.
    pub fn new(config: &MetaballConfig, r: f32) -> Metaballs {
        let m = config.resolve(r);
        Metaballs {
            cutoff: m.cutoff,
            exponent: m.exponent,
            level: m.threshold / m.scale,
        }
    }

    pub(crate) fn inv_r2(&self) -> f32 {
        1.0 / (self.cutoff * self.cutoff)
    }

    /// Σ t_i^α at `x` over `centres` (in their order): the field is T − c·this.
    #[cfg(test)]
    pub fn sum_at(&self, centres: impl IntoIterator<Item = Vec3>, x: Vec3) -> f32 {
        let inv_r2 = self.inv_r2();
        let mut sum = 0.0;
        for p in centres {
            let t = 1.0 - (x - p).length_squared() * inv_r2;
            if t > 0.0 {
                sum += t.powi(self.exponent);
            }
        }
        sum
    }

    /// Whether `x` is inside the fluid (f(x) ≤ 0).
    #[cfg(test)]
    pub fn inside(&self, centres: impl IntoIterator<Item = Vec3>, x: Vec3) -> bool {
        self.sum_at(centres, x) >= self.level
    }

    /// The radius of a lone metaball's surface: R·√(1 − (T/c)^(1/α)).
    pub fn lone_radius(&self) -> f32 {
        self.max_radius(1)
    }

    /// The paper's r_max (Sec. 5.3.1): the surface made by at most `n` metaballs lies within
    /// this distance of one of their centres, R·√(1 − (T/(c·n))^(1/α)).
    pub fn max_radius(&self, n: usize) -> f32 {
        if n == 0 {
            return 0.0;
        }
        let x = (self.level / n as f32).powf(1.0 / self.exponent as f32);
        if x >= 1.0 {
            return 0.0;
        }
        self.cutoff * (1.0 - x).sqrt()
    }
}
