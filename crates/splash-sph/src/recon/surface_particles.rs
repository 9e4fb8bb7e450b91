//! Surface particles (Sec. 4): the smoothed colour field of Müller et al. 2003 flags the
//! particles of the main body's surface; particles with few neighbours (splashes, whose colour
//! field gradient vanishes by symmetry) are flagged as well.

use std::f32::consts::PI;

use glam::Vec3;

use crate::config::Params;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::{LANES, Neighbourhood, map_particles};

pub struct SurfaceCriteria {
    /// Colour field support h; also the neighbour count radius.
    pub support: f32,
    /// Particle volume m/ρ, r³ for particles at spacing r.
    pub volume: f32,
    /// Threshold on the dimensionless |∇c|·h.
    pub colour_threshold: f32,
    pub min_neighbours: u32,
}

impl SurfaceCriteria {
    pub fn of(params: &Params) -> SurfaceCriteria {
        SurfaceCriteria {
            support: params.colour_support,
            volume: params.spacing.powi(3),
            colour_threshold: params.colour_threshold,
            min_neighbours: params.min_neighbours,
        }
    }
}

/// Positions of the surface particles, in handler order.
pub fn surface_particles(handlers: &HandlerArray, criteria: &SurfaceCriteria) -> Vec<Vec3> {
    let h = criteria.support;
    // |∇c|·h for the poly6 kernel W = 315/(64π h⁹)(h² − d²)³ written with q = d/h:
    // ∇c = −V·945/(32π h⁴) Σ (1 − q²)² (x_i − x_j)/h.
    let scale = criteria.volume * 945.0 / (32.0 * PI * h.powi(3));
    let inv_h2 = 1.0 / (h * h);
    let flags = map_particles(handlers, h, |near, x| {
        let (gradient, neighbours) = colour_gradient(near, x, inv_h2);
        // Neighbours at the particle's own position (itself, duplicates) are not counted: a
        // point mass of 30 coincident particles has a zero gradient by symmetry and would
        // otherwise count as inside, leaving no surface particle and an empty mesh.
        neighbours < criteria.min_neighbours as f32
            || gradient.length() * scale > criteria.colour_threshold
    });
    handlers
        .positions
        .iter()
        .zip(&flags)
        .filter_map(|(&p, &s)| s.then_some(p))
        .collect()
}

/// Returns Σ (1 − q²)² (x − x_j)/h and the number of particles with 0 < q < 1 (particles at
/// `x` itself are left out). Inlined into the per-particle closure, where its lane loop
/// vectorises best (left out of line, it took 15 % longer on cbd-large).
#[inline(always)]
fn colour_gradient(near: &Neighbourhood, x: Vec3, inv_h2: f32) -> (Vec3, f32) {
    // The same loop compiled once more for AVX2's 8 lanes, chosen at run time (as `lane_sums!`
    // does; the macro's term arrays would not vectorise the neighbour count).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn avx2(near: &Neighbourhood, x: Vec3, inv_h2: f32) -> (Vec3, f32) {
        lanes(near, x, inv_h2)
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above.
        return unsafe { avx2(near, x, inv_h2) };
    }
    lanes(near, x, inv_h2)
}

#[inline(always)]
fn lanes(near: &Neighbourhood, x: Vec3, inv_h2: f32) -> (Vec3, f32) {
    let inv_h = inv_h2.sqrt();
    let mut g = [[0.0f32; LANES]; 3];
    let mut count = [0.0f32; LANES];
    for ((cx, cy), cz) in near
        .x
        .chunks_exact(LANES)
        .zip(near.y.chunks_exact(LANES))
        .zip(near.z.chunks_exact(LANES))
    {
        for l in 0..LANES {
            let (dx, dy, dz) = (x.x - cx[l], x.y - cy[l], x.z - cz[l]);
            let q2 = (dx * dx + dy * dy + dz * dz) * inv_h2;
            let t = (1.0 - q2).max(0.0);
            let w = t * t;
            g[0][l] += w * dx;
            g[1][l] += w * dy;
            g[2][l] += w * dz;
            count[l] += if q2 < 1.0 && q2 > 0.0 { 1.0 } else { 0.0 };
        }
    }
    let sum = |a: &[f32; LANES]| a.iter().sum::<f32>();
    (
        Vec3::new(sum(&g[0]), sum(&g[1]), sum(&g[2])) * inv_h,
        sum(&count),
    )
}
